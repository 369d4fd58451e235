#include "moslam/dense/export.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "moslam/eval/trajectory_alignment.h"
#include "moslam/eval/trajectory_io.h"
#include "moslam/io/dataset.h"
#include "moslam/io/image.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/util/atomic_file.h"
#include "moslam/util/error.h"

namespace moslam::dense {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

void ExportOptions::Check() const {
  if (run_dir.empty()) throw InputError("map export: no run folder given");
  fusion.Check();
  stereo.Check();
  render.Check();
  if (max_depth && !(*max_depth > fusion.min_depth && std::isfinite(*max_depth))) {
    throw InputError(fmt::format("map export: --max-depth must be > {} m, got {}", fusion.min_depth,
                                 *max_depth));
  }
  if (masks == ExportMasks::kSource) mask_source.Check();
}

namespace {

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// What a run's summary.json says about its input.
struct RunInfo {
  io::DatasetFormat format = io::DatasetFormat::kAuto;
  std::string dataset;
  std::string settings;
};

RunInfo ReadRunInfo(const std::string& run_dir) {
  const std::string path = (fs::path(run_dir) / "summary.json").string();
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot read it (is " + run_dir + " a `moslam run` folder?)");
  nlohmann::json summary;
  try {
    summary = nlohmann::json::parse(in);
    RunInfo info;
    const std::string format = summary.at("dataset").at("format").get<std::string>();
    // A monocular run (an image folder, KITTI with --monocular, a video) has no depth to fuse,
    // whatever its data set holds; the summary says which sensor ran. A video's format is no
    // data set that io::ReadDataset could read back, so this comes before parsing it.
    if (summary.at("dataset").value("sensor", "") == "monocular") {
      throw InputError(path + ": a " + (format == "video" ? "video" : "monocular") +
                       " run is monocular, it has no depth to fuse (RGB-D or stereo)");
    }
    // Live sources keep no frames, and a bag's are read by sensors/, which dense/ does not use.
    if (format == "camera" || format == "kinect" || format == "rosbag") {
      throw InputError(path + ": a " + format + " run: its keyframes' depth is not in a data-set " +
                       "folder (map export reads TUM, KITTI and EuRoC folders)");
    }
    const auto parsed = io::ParseDatasetFormat(format);
    if (!parsed) throw InputError(path + ": unknown dataset.format '" + format + "'");
    info.format = *parsed;
    info.dataset = summary.at("dataset").at("path").get<std::string>();
    info.settings = summary.at("settings").at("path").get<std::string>();
    return info;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not the summary of a run (" + e.what() + ")");
  }
}

// The frame of each keyframe, by its stamp (KeyFrameTrajectory.txt prints 6 decimals).
std::vector<const io::FrameEntry*> MatchFrames(const io::Sequence& sequence,
                                               const eval::Trajectory& keyframes,
                                               const std::string& path) {
  std::vector<const io::FrameEntry*> frames;
  for (double t : keyframes.timestamps) {
    const auto it =
        std::lower_bound(sequence.frames.begin(), sequence.frames.end(), t - 1e-4,
                         [](const io::FrameEntry& f, double stamp) { return f.timestamp < stamp; });
    if (it == sequence.frames.end() || std::abs(it->timestamp - t) > 1e-4) {
      throw InputError(
          fmt::format("{}: keyframe {:.6f} is no frame of {}", path, t, sequence.root));
    }
    frames.push_back(&*it);
  }
  return frames;
}

// The keyframes' poses in the ground truth's frame (SE(3) alignment of the keyframe positions).
std::vector<geometry::SE3> AlignToGroundTruth(const io::Sequence& sequence,
                                              const eval::Trajectory& keyframes,
                                              const eval::Trajectory& gt) {
  eval::Trajectory gt_matched, est_matched;
  for (size_t i = 0; i < keyframes.size(); ++i) {
    const auto it = std::lower_bound(gt.timestamps.begin(), gt.timestamps.end(),
                                     keyframes.timestamps[i] - 1e-4);
    if (it == gt.timestamps.end() || std::abs(*it - keyframes.timestamps[i]) > 1e-4) continue;
    const auto k = static_cast<size_t>(std::distance(gt.timestamps.begin(), it));
    gt_matched.timestamps.push_back(*it);
    gt_matched.poses.push_back(gt.poses[k]);
    est_matched.timestamps.push_back(keyframes.timestamps[i]);
    est_matched.poses.push_back(keyframes.poses[i]);
  }
  gt_matched.name = *sequence.ground_truth_path;
  est_matched.name = keyframes.name;
  const geometry::Sim3 S = eval::EstimateAlignment(
      gt_matched, est_matched, eval::AlignmentMode::kSe3, eval::AlignmentSolver::kUmeyama);
  const geometry::SE3 T_gt_est(S.rotation(), S.translation());
  std::vector<geometry::SE3> poses;
  for (const geometry::SE3& T : keyframes.poses) poses.push_back(T_gt_est * T);
  return poses;
}

struct Input {
  io::Sequence sequence;
  io::OrbSlamSettings settings;
  Intrinsics intrinsics;
};

Input ReadInput(const RunInfo& info) {
  Input in;
  io::DatasetOptions dataset;
  dataset.format = info.format;
  in.sequence = io::ReadDataset(info.dataset, dataset);
  if (in.sequence.sensor == io::SensorType::kMonocular) {
    throw InputError(info.dataset + ": a monocular run has no depth to fuse (RGB-D or stereo)");
  }
  in.settings = io::LoadOrbSlamSettings(info.settings, in.sequence.sensor);
  const camera::PinholeOptions& c = in.settings.camera;
  in.intrinsics = {c.fx, c.fy, c.cx, c.cy};
  return in;
}

DepthView LoadView(const Input& in, const io::FrameEntry& frame, const StereoDepthOptions& stereo) {
  const io::FrameImages images =
      io::LoadFrameImages(frame, io::ColourMode::kColour, in.settings.depth_map_factor);
  DepthView view;
  view.colour = images.left;
  view.depth = in.sequence.sensor == io::SensorType::kRgbD
                   ? images.depth
                   : DepthFromStereo(images.left, images.right, in.settings.bf, stereo);
  return view;
}

cv::Mat RunMask(const std::string& run_dir, double stamp) {
  const std::string path = fmt::format("{}/keyframe_masks/{:.6f}.png", run_dir, stamp);
  if (!fs::exists(path)) return {};
  return io::LoadGreyImage(path);
}

// The generator's noise-free depth (`moslam synth --exact-depth`: depth_gt/ beside depth/), when
// it was written: Kinect-type noise of 1-2 cm at 3-4 m makes a surface two or three 5 cm voxels
// thick, so the truth is better drawn without it.
std::optional<cv::Mat> ExactDepth(const Input& in, const io::FrameEntry& frame) {
  if (frame.depth.empty()) return std::nullopt;
  std::string path = frame.depth;
  const size_t at = path.rfind("/depth/");
  if (at == std::string::npos) return std::nullopt;
  path.replace(at, 7, "/depth_gt/");
  if (!fs::exists(path)) return std::nullopt;
  return io::LoadDepthImage(path, in.settings.depth_map_factor);
}

// The ground truth's voxel sets: where the people were in any frame (ground-truth masks, every
// frame, at its ground-truth pose) and the static scene the keyframes saw.
struct TruthSets {
  VoxelSet people, statics;
  explicit TruthSets(double resolution) : people(resolution), statics(resolution) {}
};

TruthSets BuildTruth(const Input& in, const eval::Trajectory& gt,
                     const std::vector<const io::FrameEntry*>& keyframe_frames,
                     const DenseFusionOptions& fusion, const StereoDepthOptions& stereo) {
  runner::MaskOptions truth_masks;
  truth_masks.kind = runner::MaskSourceKind::kSynthGt;
  const auto source = runner::MakeMaskSource(truth_masks, in.sequence);
  TruthSets sets(fusion.resolution);
  DenseFusionOptions exact = fusion;
  exact.mask_margin_px = 0;
  const auto pose_at = [&](double t) -> std::optional<geometry::SE3> {
    const auto it = std::lower_bound(gt.timestamps.begin(), gt.timestamps.end(), t - 1e-4);
    if (it == gt.timestamps.end() || std::abs(*it - t) > 1e-4) return std::nullopt;
    return gt.poses[static_cast<size_t>(std::distance(gt.timestamps.begin(), it))];
  };
  for (const io::FrameEntry& frame : in.sequence.frames) {
    const auto pose = pose_at(frame.timestamp);
    if (!pose) continue;
    DepthView view = LoadView(in, frame, stereo);
    if (const auto exact = ExactDepth(in, frame)) view.depth = *exact;
    view.T_world_cam = *pose;
    view.mask = source->MaskFor(frame, view.depth.size()).mask;
    sets.people.Add(BackProject(in.intrinsics, exact, view, MaskUse::kOnly, nullptr, nullptr));
    if (std::find(keyframe_frames.begin(), keyframe_frames.end(), &frame) !=
        keyframe_frames.end()) {
      sets.statics.Add(
          BackProject(in.intrinsics, exact, view, MaskUse::kLeaveOut, nullptr, nullptr));
    }
  }
  return sets;
}

nlohmann::json ReportJson(const ExportOptions& options, const ExportResult& r) {
  nlohmann::json j;
  j["run_dir"] = options.run_dir;
  j["masks"] = options.masks == ExportMasks::kRun    ? "run"
               : options.masks == ExportMasks::kNone ? "none"
                                                     : runner::ToString(options.mask_source.kind);
  j["resolution_m"] = options.fusion.resolution;
  j["pixel_step"] = options.fusion.pixel_step;
  j["max_depth_m"] = options.fusion.max_depth;
  j["mask_margin_px"] = options.fusion.mask_margin_px;
  j["keyframes"] = r.keyframes;
  j["masked_keyframes"] = r.masked_frames;
  j["rays"] = r.rays.rays;
  j["masked_pixels"] = r.rays.masked;
  j["occupied_voxels"] = r.occupied;
  j["fusion_s"] = r.fusion_s;
  j["total_s"] = r.total_s;
  if (r.scores) {
    const DenseMapScores& s = *r.scores;
    j["scores"] = {{"occupied", s.occupied},
                   {"in_people", s.in_people},
                   {"people_fraction", s.people_fraction},
                   {"static_seen", s.static_seen},
                   {"static_occupied", s.static_occupied},
                   {"static_occupied_near", s.static_occupied_near},
                   {"completeness", s.completeness},
                   {"completeness_near", s.completeness_near}};
  } else {
    j["scores"] = nullptr;
  }
  return j;
}

// The map's vertical: the keyframes' image up direction (-y of the camera), averaged; its
// largest component names the axis.
void SetUpAxis(const std::vector<geometry::SE3>& poses, RenderOptions* render) {
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const geometry::SE3& T : poses) up -= T.rotation_matrix().col(1);
  if (up.norm() == 0.0) return;
  Eigen::Index axis = 0;
  up.cwiseAbs().maxCoeff(&axis);
  render->up_axis = static_cast<int>(axis);
  render->up_positive = up[axis] > 0.0;
}

void WriteOutputs(const DenseFusion& fusion, const std::vector<Voxel>& voxels,
                  const std::vector<geometry::SE3>& poses, const ExportOptions& options,
                  ExportResult* r) {
  r->octree = (fs::path(options.out) / "map.bt").string();
  r->cloud = (fs::path(options.out) / "map.ply").string();
  r->picture = (fs::path(options.out) / "map_top.png").string();
  r->report = (fs::path(options.out) / "export.json").string();
  fusion.WriteBinary(r->octree);
  WritePly(voxels, r->cloud);
  // As a floor plan is drawn: cut above the cameras (0.5 m over the highest keyframe), or an
  // indoor map shows its ceiling.
  const int h = options.render.up_axis;
  const double sign = options.render.up_positive ? 1.0 : -1.0;
  double top = -std::numeric_limits<double>::infinity();
  for (const geometry::SE3& T : poses) top = std::max(top, sign * T.translation()[h] + 0.5);
  std::vector<Voxel> below;
  for (const Voxel& v : voxels) {
    if (sign * v.centre[h] <= top) below.push_back(v);
  }
  std::vector<uint8_t> png;
  cv::imencode(".png", RenderTopView(below, options.fusion.resolution, options.render), png);
  WriteFileAtomically(r->picture,
                      std::string_view(reinterpret_cast<const char*>(png.data()), png.size()),
                      "picture");
}

}  // namespace

ExportResult ExportDenseMap(const ExportOptions& given) {
  const auto start = Clock::now();
  ExportOptions options = given;
  options.Check();
  if (options.out.empty()) options.out = (fs::path(options.run_dir) / "dense").string();
  const RunInfo info = ReadRunInfo(options.run_dir);
  const Input in = ReadInput(info);
  options.fusion.max_depth =
      options.max_depth.value_or(in.sequence.sensor == io::SensorType::kRgbD ? 4.0 : 30.0);
  options.fusion.Check();
  const std::string kf_path = (fs::path(options.run_dir) / "KeyFrameTrajectory.txt").string();
  const eval::Trajectory keyframes = eval::ReadTum(kf_path);
  const std::vector<const io::FrameEntry*> frames = MatchFrames(in.sequence, keyframes, kf_path);
  std::vector<geometry::SE3> poses = keyframes.poses;
  std::optional<eval::Trajectory> gt;
  if (options.score) {
    if (!in.sequence.ground_truth_path) {
      throw InputError(info.dataset + ": --score needs the data set's ground truth");
    }
    gt = eval::ReadTrajectory(*in.sequence.ground_truth_path);
    poses = AlignToGroundTruth(in.sequence, keyframes, *gt);
  }
  std::unique_ptr<runner::MaskSource> source;
  if (options.masks == ExportMasks::kSource) {
    source = runner::MakeMaskSource(options.mask_source, in.sequence);
  }
  SetUpAxis(poses, &options.render);
  fs::create_directories(options.out);
  DenseFusion fusion(in.intrinsics, options.fusion);
  ExportResult r;
  for (size_t i = 0; i < frames.size(); ++i) {
    DepthView view = LoadView(in, *frames[i], options.stereo);
    view.T_world_cam = poses[i];
    if (options.masks == ExportMasks::kRun)
      view.mask = RunMask(options.run_dir, keyframes.timestamps[i]);
    if (source) view.mask = source->MaskFor(*frames[i], view.depth.size()).mask;
    const auto t0 = Clock::now();
    const InsertStats stats = fusion.Insert(view);
    r.fusion_s += Seconds(t0);
    r.rays.rays += stats.rays;
    r.rays.masked += stats.masked;
    r.rays.invalid += stats.invalid;
    r.masked_frames += view.mask.empty() ? 0 : 1;
    ++r.keyframes;
    spdlog::debug("map export: keyframe {:.6f}: {} rays, {} masked", keyframes.timestamps[i],
                  stats.rays, stats.masked);
  }
  const std::vector<Voxel> voxels = fusion.OccupiedVoxels();
  r.occupied = voxels.size();
  if (gt) {
    const TruthSets truth = BuildTruth(in, *gt, frames, options.fusion, options.stereo);
    r.scores = ScoreDenseMap(voxels, truth.people, truth.statics);
  }
  WriteOutputs(fusion, voxels, poses, options, &r);
  r.total_s = Seconds(start);
  WriteFileAtomically(r.report, ReportJson(options, r).dump(2) + "\n", "export report");
  return r;
}

}  // namespace moslam::dense
