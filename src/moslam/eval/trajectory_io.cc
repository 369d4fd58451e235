#include "moslam/eval/trajectory_io.h"

#include <cmath>
#include <fstream>
#include <optional>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "moslam/geometry/so3.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::eval {
namespace {

// Parses every field of a line as a number, naming the first one that is not.
std::vector<double> ParseNumbers(const std::string& path, const TextLine& line, bool commas) {
  const std::vector<std::string_view> fields = SplitFields(line.text, commas);
  std::vector<double> values;
  values.reserve(fields.size());
  for (size_t k = 0; k < fields.size(); ++k) {
    const std::optional<double> v = ParseDouble(fields[k]);
    if (!v) {
      ThrowAtLine(path, line.number,
                  fmt::format("field {} ('{}') is not a number", k + 1, Excerpt(fields[k])));
    }
    values.push_back(*v);
  }
  return values;
}

bool AnyNan(const std::vector<double>& values) {
  for (const double v : values) {
    if (std::isnan(v)) return true;
  }
  return false;
}

void RequireFinite(const std::string& path, const TextLine& line, const std::vector<double>& v) {
  for (size_t k = 0; k < v.size(); ++k) {
    if (!std::isfinite(v[k])) {
      ThrowAtLine(path, line.number, fmt::format("field {} is not finite ({})", k + 1, v[k]));
    }
  }
}

// Collects the TUM-style skips (NaN lines, zero quaternions) for one warning per kind.
struct Skips {
  int nan_lines = 0;
  int first_nan_line = 0;
  int zero_quaternions = 0;
  int first_zero_line = 0;
  void Report(const std::string& path) const {
    if (nan_lines > 0) {
      spdlog::warn("{}: skipped {} line(s) with NaNs (first: line {}), as TUM's tools do", path,
                   nan_lines, first_nan_line);
    }
    if (zero_quaternions > 0) {
      spdlog::warn("{}: skipped {} pose(s) with an all-zero quaternion (first: line {})", path,
                   zero_quaternions, first_zero_line);
    }
  }
};

// Positions are metres: beyond 1e9 m (six times the Earth-Sun distance) a value is a typo or
// garbage, and the squares the alignment sums overflow long before 1e300 (issue 31: a position
// of -1e300 made the ATE report positions that "do not determine the transform").
constexpr double kMaxPositionMetres = 1e9;

void RequirePlausiblePosition(const std::string& path, const TextLine& line,
                              const Eigen::Vector3d& t) {
  if (t.allFinite() && t.cwiseAbs().maxCoeff() > kMaxPositionMetres) {
    ThrowAtLine(path, line.number,
                fmt::format("position ({}, {}, {}) lies beyond {:g} m; trajectories are in metres",
                            t.x(), t.y(), t.z(), kMaxPositionMetres));
  }
}

// Appends one stamped pose, enforcing the ordering rule of trajectory_io.h.
void AddStampedPose(const std::string& path, const TextLine& line, double stamp,
                    const Eigen::Vector3d& t, const Eigen::Quaterniond& q, int* previous_line,
                    int* repeats, Trajectory* out) {
  if (!std::isfinite(stamp)) ThrowAtLine(path, line.number, "timestamp is not finite");
  const double n = q.norm();
  if (!std::isfinite(n) || n < 1e-6 || !t.allFinite()) {
    ThrowAtLine(
        path, line.number,
        fmt::format("invalid pose (quaternion norm {}, translation finite: {})", n, t.allFinite()));
  }
  RequirePlausiblePosition(path, line, t);
  if (!out->timestamps.empty()) {
    const double last = out->timestamps.back();
    if (stamp < last) {
      ThrowAtLine(path, line.number,
                  fmt::format("timestamp {:.6f} is earlier than {:.6f} on line {}; trajectory "
                              "files must be sorted by time",
                              stamp, last, *previous_line));
    }
    if (stamp == last) {
      if (*repeats == 0) {
        spdlog::warn("{}:{}: timestamp {:.6f} repeats line {}; both poses kept", path, line.number,
                     stamp, *previous_line);
      }
      ++*repeats;
    }
  }
  *previous_line = line.number;
  out->timestamps.push_back(stamp);
  out->poses.emplace_back(q, t);
}

// The first line of the file, raw (ReadDataLines drops '#' lines, which carry EuRoC's header).
std::string FirstLine(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

std::ofstream OpenForWriting(const std::string& path) {
  std::ofstream out(path);
  if (!out) ThrowInFile(path, "cannot be opened for writing");
  return out;
}

void RequireStamps(const Trajectory& trajectory, const std::string& path) {
  if (!trajectory.has_timestamps()) {
    ThrowInFile(path, fmt::format("cannot write '{}' in a stamped format: it has no timestamps",
                                  trajectory.name));
  }
}

}  // namespace

TrajectoryFormat ParseTrajectoryFormat(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "auto") return TrajectoryFormat::kAuto;
  if (lower == "tum") return TrajectoryFormat::kTum;
  if (lower == "kitti") return TrajectoryFormat::kKitti;
  if (lower == "euroc") return TrajectoryFormat::kEuroc;
  ThrowInput("unknown trajectory format '{}' (auto, tum, kitti, euroc)", name);
}

const char* TrajectoryFormatName(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kAuto:
      return "auto";
    case TrajectoryFormat::kTum:
      return "tum";
    case TrajectoryFormat::kKitti:
      return "kitti";
    case TrajectoryFormat::kEuroc:
      return "euroc";
  }
  return "?";
}

TrajectoryFormat DetectTrajectoryFormat(const std::string& path) {
  if (EndsWith(ToLower(path), ".csv")) return TrajectoryFormat::kEuroc;
  const std::vector<TextLine> lines = ReadDataLines(path);
  const std::string first = FirstLine(path);
  if (StartsWith(Trim(first), "#") && first.find("p_RS_R") != std::string::npos) {
    return TrajectoryFormat::kEuroc;
  }
  if (lines.empty()) ThrowInFile(path, "has no data lines; cannot tell its format");
  const TextLine& line = lines.front();
  if (line.text.find(',') != std::string::npos) return TrajectoryFormat::kEuroc;
  const size_t n = SplitFields(line.text).size();
  if (n == 8) return TrajectoryFormat::kTum;
  if (n == 12) return TrajectoryFormat::kKitti;
  ThrowAtLine(path, line.number,
              fmt::format("cannot tell the trajectory format from {} fields (TUM has 8, KITTI 12, "
                          "EuRoC is comma-separated); name it with a --*-format option",
                          n));
}

Trajectory ReadTrajectory(const std::string& path, TrajectoryFormat format) {
  if (format == TrajectoryFormat::kAuto) format = DetectTrajectoryFormat(path);
  switch (format) {
    case TrajectoryFormat::kTum:
      return ReadTum(path);
    case TrajectoryFormat::kKitti:
      return ReadKitti(path);
    case TrajectoryFormat::kEuroc:
      return ReadEuroc(path);
    case TrajectoryFormat::kAuto:
      break;
  }
  ThrowInFile(path, "no trajectory format");
}

namespace {

// The field layout of a text trajectory with one stamped pose per line (TUM, EuRoC).
struct StampedLayout {
  bool exact_count;         // exactly 8 fields (TUM) or at least 8 (EuRoC has velocities after)
  const char* fields_text;  // for the error message
  bool w_first;             // quaternion stored w, x, y, z (EuRoC) instead of x, y, z, w (TUM)
  double stamp_divisor;     // stamp units per second; a division, as evo converts nanoseconds
};

// Reads `path` line by line: NaN lines and all-zero quaternions are skipped and reported once,
// as TUM's tools do; the rest go through AddStampedPose's ordering rule.
Trajectory ReadStamped(const std::string& path, const StampedLayout& layout) {
  Trajectory out;
  out.name = path;
  Skips skips;
  int previous_line = 0;
  int repeats = 0;
  for (const TextLine& line : ReadDataLines(path)) {
    const std::vector<double> v = ParseNumbers(path, line, /*commas=*/true);
    if (layout.exact_count ? v.size() != 8 : v.size() < 8) {
      ThrowAtLine(path, line.number,
                  fmt::format("expected {}8 fields ({}), found {}",
                              layout.exact_count ? "" : "at least ", layout.fields_text, v.size()));
    }
    if (AnyNan(v)) {
      if (skips.nan_lines++ == 0) skips.first_nan_line = line.number;
      continue;
    }
    if (v[4] == 0 && v[5] == 0 && v[6] == 0 && v[7] == 0) {
      if (skips.zero_quaternions++ == 0) skips.first_zero_line = line.number;
      continue;
    }
    const Eigen::Quaterniond q = layout.w_first ? Eigen::Quaterniond(v[4], v[5], v[6], v[7])
                                                : Eigen::Quaterniond(v[7], v[4], v[5], v[6]);
    AddStampedPose(path, line, v[0] / layout.stamp_divisor, {v[1], v[2], v[3]}, q, &previous_line,
                   &repeats, &out);
  }
  skips.Report(path);
  return out;
}

}  // namespace

Trajectory ReadTum(const std::string& path) {
  return ReadStamped(path, {true, "timestamp tx ty tz qx qy qz qw", false, 1.0});
}

Trajectory ReadEuroc(const std::string& path) {
  return ReadStamped(path, {false, "timestamp_ns, p_x, p_y, p_z, q_w, q_x, q_y, q_z", true, 1e9});
}

Trajectory ReadKitti(const std::string& path) {
  Trajectory out;
  out.name = path;
  for (const TextLine& line : ReadDataLines(path)) {
    const std::vector<double> v = ParseNumbers(path, line, /*commas=*/false);
    if (v.size() != 12) {
      ThrowAtLine(path, line.number,
                  fmt::format("expected 12 fields (row-major 3x4 pose), found {}", v.size()));
    }
    RequireFinite(path, line, v);
    geometry::Matrix3x4d m;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) m(r, c) = v[static_cast<size_t>(4 * r + c)];
    }
    const Eigen::Matrix3d R = m.leftCols<3>();
    const double off = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
    if (!(off < 1e-2) || R.determinant() <= 0) {
      ThrowAtLine(
          path, line.number,
          fmt::format("the 3x3 block is not a rotation (|R^T R - I| = {:.3g}, det = {:.3g})", off,
                      R.determinant()));
    }
    RequirePlausiblePosition(path, line, m.col(3));
    out.poses.push_back(geometry::SE3::FromMatrix3x4(m));
    out.raw_rotations.push_back(R);
  }
  return out;
}

std::vector<double> ReadTimes(const std::string& path) {
  std::vector<double> times;
  int previous_line = 0;
  for (const TextLine& line : ReadDataLines(path)) {
    const std::vector<double> v = ParseNumbers(path, line, /*commas=*/false);
    if (v.size() != 1) {
      ThrowAtLine(path, line.number,
                  fmt::format("expected 1 timestamp, found {} fields", v.size()));
    }
    if (!std::isfinite(v[0])) ThrowAtLine(path, line.number, "timestamp is not finite");
    if (!times.empty() && v[0] < times.back()) {
      ThrowAtLine(path, line.number,
                  fmt::format("timestamp {} is earlier than {} on line {}", v[0], times.back(),
                              previous_line));
    }
    previous_line = line.number;
    times.push_back(v[0]);
  }
  return times;
}

void AttachTimes(const std::string& times_path, Trajectory* trajectory) {
  std::vector<double> times = ReadTimes(times_path);
  if (times.size() != trajectory->size()) {
    ThrowInFile(times_path, fmt::format("has {} timestamps but '{}' has {} poses", times.size(),
                                        trajectory->name, trajectory->size()));
  }
  trajectory->timestamps = std::move(times);
}

void WriteTum(const Trajectory& trajectory, const std::string& path) {
  RequireStamps(trajectory, path);
  std::ofstream out = OpenForWriting(path);
  out << "# timestamp tx ty tz qx qy qz qw\n";
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const Eigen::Vector3d& t = trajectory.Position(i);
    const Eigen::Quaterniond& q = trajectory.poses[i].rotation();
    out << fmt::format("{} {} {} {} {} {} {} {}\n", trajectory.timestamps[i], t.x(), t.y(), t.z(),
                       q.x(), q.y(), q.z(), q.w());
  }
  if (!out) ThrowInFile(path, "write error");
}

void WriteKitti(const Trajectory& trajectory, const std::string& path) {
  std::ofstream out = OpenForWriting(path);
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const Eigen::Matrix4d m = trajectory.Matrix(i);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) out << fmt::format(r + c == 0 ? "{}" : " {}", m(r, c));
    }
    out << '\n';
  }
  if (!out) ThrowInFile(path, "write error");
}

void WriteEuroc(const Trajectory& trajectory, const std::string& path) {
  RequireStamps(trajectory, path);
  std::ofstream out = OpenForWriting(path);
  out << "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],"
         "q_RS_z []\n";
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const Eigen::Vector3d& t = trajectory.Position(i);
    const Eigen::Quaterniond& q = trajectory.poses[i].rotation();
    out << fmt::format("{},{},{},{},{},{},{},{}\n", std::llround(trajectory.timestamps[i] * 1e9),
                       t.x(), t.y(), t.z(), q.w(), q.x(), q.y(), q.z());
  }
  if (!out) ThrowInFile(path, "write error");
}

}  // namespace moslam::eval
