#include "moslam/io/kitti.h"

#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "moslam/io/image.h"
#include "moslam/io/index_file.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::io {
namespace {

namespace fs = std::filesystem;

geometry::Matrix3x4d ParseProjection(const std::string& path, const TextLine& line,
                                     const std::vector<std::string_view>& values) {
  if (values.size() != 12) {
    ThrowAtLine(
        path, line.number,
        fmt::format("expected 12 values of a 3x4 projection matrix, got {}", values.size()));
  }
  geometry::Matrix3x4d P;
  for (int k = 0; k < 12; ++k) {
    const std::optional<double> v = ParseDouble(values[k]);
    if (!v || !std::isfinite(*v)) {
      ThrowAtLine(path, line.number,
                  fmt::format("value {} '{}' is not a finite number", k + 1, Excerpt(values[k])));
    }
    P(k / 4, k % 4) = *v;  // row-major
  }
  return P;
}

// The label of a "P2: ..." line without its colon, or empty when the line has none.
std::string_view LabelOf(std::string_view first_field) {
  return EndsWith(first_field, ":") ? first_field.substr(0, first_field.size() - 1)
                                    : std::string_view();
}

std::string ImagePath(const std::string& folder, const std::string& camera_dir, size_t index) {
  return (fs::path(folder) / camera_dir / fmt::format("{:06d}.png", index)).string();
}

// Rethrows an InputError from a check without file context as one naming `path`.
template <typename F>
auto InFile(const std::string& path, const std::string& what, F f) {
  try {
    return f();
  } catch (const InputError& e) {
    ThrowInFile(path, fmt::format("{}: {}", what, e.what()));
  }
}

}  // namespace

KittiCalibration ReadKittiCalibration(const std::string& path) {
  KittiCalibration calibration;
  int unlabelled = 0;
  int labelled = 0;
  for (const TextLine& line : ReadDataLines(path)) {
    std::vector<std::string_view> fields = SplitFields(line.text);
    const std::string_view label = LabelOf(fields.front());
    int camera = -1;
    if (label.empty()) {
      if (labelled > 0) {
        ThrowAtLine(path, line.number, "unlabelled line among 'Pi:' lines: cannot tell the camera");
      }
      if (unlabelled == 4) ThrowAtLine(path, line.number, "more than four unlabelled P lines");
      camera = unlabelled++;
    } else {
      if (StartsWith(label, "Tr") || label == "R0_rect") continue;  // not used by moslam
      if (unlabelled > 0) {
        ThrowAtLine(path, line.number, "labelled line after unlabelled lines: cannot tell cameras");
      }
      if (label.size() != 2 || label[0] != 'P' || label[1] < '0' || label[1] > '3') {
        ThrowAtLine(path, line.number, fmt::format("unknown label '{}:'", Excerpt(label)));
      }
      camera = label[1] - '0';
      if (calibration.P[camera]) {
        ThrowAtLine(path, line.number, fmt::format("camera P{} given twice", camera));
      }
      ++labelled;
      fields.erase(fields.begin());
    }
    calibration.P[camera] = ParseProjection(path, line, fields);
  }
  if (!calibration.P[0] && !calibration.P[2]) ThrowInFile(path, "has no projection matrices");
  return calibration;
}

camera::PinholeOptions IntrinsicsFromProjection(const geometry::Matrix3x4d& P) {
  // A rectified camera's P is K [I | t]: no skew, last row (0 0 1 t_z).
  constexpr double kTol = 1e-9;
  if (std::abs(P(0, 1)) > kTol || std::abs(P(1, 0)) > kTol || std::abs(P(2, 0)) > kTol ||
      std::abs(P(2, 1)) > kTol || std::abs(P(2, 2) - 1.0) > kTol) {
    ThrowInput("projection matrix is not of the rectified form K [I | t]");
  }
  camera::PinholeOptions options;
  options.fx = P(0, 0);
  options.fy = P(1, 1);
  options.cx = P(0, 2);
  options.cy = P(1, 2);
  options.Check();
  return options;
}

double StereoBfFromProjections(const geometry::Matrix3x4d& left,
                               const geometry::Matrix3x4d& right) {
  if (!left.leftCols<3>().isApprox(right.leftCols<3>(), 1e-9)) {
    ThrowInput(
        "left and right projection matrices have different intrinsics: not a rectified "
        "stereo pair");
  }
  const double bf = -(right(0, 3) - left(0, 3));
  if (!(bf > 0.0)) {
    ThrowInput("right camera is not to the right of the left one (bf = {} <= 0)", bf);
  }
  return bf;
}

Sequence ReadKitti(const std::string& folder, const KittiOptions& options) {
  RequireDirectory(folder, "KITTI sequence folder");
  const std::string left_dir = options.colour ? "image_2" : "image_0";
  const std::string right_dir = options.colour ? "image_3" : "image_1";
  RequireDirectory((fs::path(folder) / left_dir).string(), "KITTI left image folder");
  std::error_code ec;
  const bool stereo = !options.monocular && fs::is_directory(fs::path(folder) / right_dir, ec);

  Sequence sequence;
  sequence.name = internal::FolderName(folder);
  sequence.root = folder;
  sequence.sensor = stereo ? SensorType::kStereo : SensorType::kMonocular;

  const std::string times_path = (fs::path(folder) / "times.txt").string();
  std::optional<double> previous;
  for (const TextLine& line : ReadDataLines(times_path)) {
    const auto fields = internal::SplitExactly(times_path, line, 1, false, "'seconds'");
    FrameEntry frame;
    frame.index = static_cast<int>(sequence.frames.size());
    frame.timestamp = internal::ParseSeconds(times_path, line, fields[0]);
    internal::RequireIncreasing(times_path, line, previous, frame.timestamp);
    previous = frame.timestamp;
    frame.image_left = ImagePath(folder, left_dir, sequence.frames.size());
    internal::RequireListedFile(times_path, line.number, frame.image_left);
    if (stereo) {
      frame.image_right = ImagePath(folder, right_dir, sequence.frames.size());
      internal::RequireListedFile(times_path, line.number, frame.image_right);
    }
    sequence.frames.push_back(std::move(frame));
  }
  if (sequence.frames.empty()) ThrowInFile(times_path, "lists no time stamps");

  const std::string calib_path = (fs::path(folder) / "calib.txt").string();
  const KittiCalibration calib = ReadKittiCalibration(calib_path);
  const int left_index = options.colour ? 2 : 0;
  const int right_index = left_index + 1;
  if (!calib.P[left_index]) {
    ThrowInFile(calib_path, fmt::format("has no P{} (left camera)", left_index));
  }
  SequenceCalibration calibration;
  calibration.camera = InFile(calib_path, fmt::format("P{}", left_index),
                              [&] { return IntrinsicsFromProjection(*calib.P[left_index]); });
  const cv::Mat first = LoadGreyImage(sequence.frames.front().image_left);
  calibration.camera.width = first.cols;
  calibration.camera.height = first.rows;
  InFile(calib_path, fmt::format("P{} with image size {}x{}", left_index, first.cols, first.rows),
         [&] { calibration.camera.Check(); });
  if (stereo) {
    if (!calib.P[right_index]) {
      ThrowInFile(calib_path, fmt::format("has no P{} (right camera of the stereo pair in {}/)",
                                          right_index, right_dir));
    }
    calibration.bf = InFile(calib_path, fmt::format("P{} and P{}", left_index, right_index), [&] {
      return StereoBfFromProjections(*calib.P[left_index], *calib.P[right_index]);
    });
  }
  sequence.calibration = calibration;

  if (!options.poses_path.empty()) {
    RequireFile(options.poses_path, "KITTI poses file");
    sequence.ground_truth_path = options.poses_path;
  } else {
    sequence.ground_truth_path = internal::ExistingFile(folder, "poses.txt");
  }
  return sequence;
}

}  // namespace moslam::io
