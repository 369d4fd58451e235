// Test and tool support (not used by the library): runs slam::System over a data-set folder and
// scores the camera and keyframe trajectories against the ground truth with the TUM-convention
// ATE (SE(3) alignment; Sim(3) for monocular runs, whose scale is arbitrary). apps/moslam's `run`
// command is the user-facing path; this is the small loop the end-to-end tests and tools/slam_eval
// need.
#pragma once

#include <time.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "moslam/eval/ate.h"
#include "moslam/eval/statistics.h"
#include "moslam/eval/trajectory_io.h"
#include "moslam/feature/orb_extractor.h"
#include "moslam/io/dataset.h"
#include "moslam/io/image.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/slam/system.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::slam {

// A small vocabulary (10^3 words) trained on every `step`-th frame's ORB descriptors of the
// data set, as the tracker extracts them: tests need no shipped vocabulary file.
inline std::shared_ptr<const vocab::Vocabulary> TrainVocabulary(const std::string& folder,
                                                                int step) {
  const io::Sequence sequence = io::ReadDataset(folder);
  const io::OrbSlamSettings settings =
      io::LoadOrbSlamSettings(folder + "/settings.yaml", sequence.sensor);
  feature::OrbExtractorOptions orb;
  orb.ApplySettings(settings.orb);
  feature::OrbExtractor extractor(orb);
  std::vector<cv::Mat> descriptors;
  for (size_t i = 0; i < sequence.size(); i += static_cast<size_t>(step)) {
    const io::FrameImages images =
        io::LoadFrameImages(sequence.frames[i], io::ColourMode::kGrey, settings.depth_map_factor);
    descriptors.push_back(extractor.Extract(images.left).descriptors);
  }
  vocab::VocabularyTrainOptions options;
  options.k = 10;
  options.levels = 3;  // 1000 words: enough to tell the walls of one room apart
  return std::make_shared<const vocab::Vocabulary>(vocab::Vocabulary::Train(descriptors, options));
}

inline std::string MaskPath(const io::FrameEntry& entry, const std::string& mask_folder) {
  std::string path = entry.image_left;
  for (const std::string folder : {"/rgb/", "/image_0/", "/image_2/"}) {
    const size_t at = path.rfind(folder);
    if (at != std::string::npos) return path.replace(at, folder.size(), "/" + mask_folder + "/");
  }
  return path;
}

// The System's input for one frame of a data set: its images loaded as `options` read them, and
// (when `mask_folder` is set) its movable-object mask from that folder (see MaskPath).
inline FrameInput LoadFrameInput(const io::FrameEntry& entry, const SystemOptions& options,
                                 const std::string& mask_folder = "") {
  const io::FrameImages images =
      io::LoadFrameImages(entry, io::ColourMode::kGrey, options.settings.depth_map_factor);
  FrameInput input;
  input.timestamp = entry.timestamp;
  input.image = images.left;
  input.right = images.right;
  input.depth = images.depth;
  if (!mask_folder.empty()) input.mask = io::LoadGreyImage(MaskPath(entry, mask_folder));
  return input;
}

struct DatasetRun {
  std::vector<FrameReport> reports;
  eval::Trajectory estimate;
  MapSummary summary;
  int frames_ok = 0;
  double ate_rmse = -1.0;           // metres, camera trajectory; < 0 without ground truth
  double keyframe_ate_rmse = -1.0;  // metres, keyframe trajectory; < 0 without ground truth
  // Scale of the best Sim(3) alignment of the camera trajectory to the ground truth (1: the
  // right scale; 0.99: the estimate is 1 % too long); 0 without ground truth.
  double sim3_scale = 0.0;
  eval::Trajectory keyframes;
  double track_ms_median = 0.0;  // FrameReport::times.total_ms (wall clock)
  // CPU time of the calling (tracking) thread per Track() call: on a machine shared with other
  // jobs, the wall clock counts time spent waiting for a core; this does not.
  double track_cpu_ms_median = 0.0;
};

inline double ThreadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

// `max_frames` <= 0: all frames. `mask_folder`: when set, each frame's movable-object mask is
// read from the image path with its "rgb" (or "image_0") folder replaced by this one (the
// layout of `moslam synth`: rgb/<stamp>.png -> moving/<stamp>.png). `adjust` (may be empty) edits
// the SystemOptions before the run (experiments: local BA off, ...). `realtime`: frames are
// handed over no faster than their timestamps, as a camera would (ORB-SLAM2's examples wait the
// same way), so threaded local mapping gets the time a live run gives it; without it frames come
// as fast as tracking takes them, which starves mapping on a loaded machine. `edit_mask` (may be
// empty) changes each frame's mask before tracking (frame index, mask): damage for the tests of
// imperfect masks.
inline DatasetRun RunDataset(const std::string& folder, const std::string& settings_path,
                             bool deterministic, int max_frames = 0,
                             const std::string& mask_folder = "",
                             const std::function<void(SystemOptions*)>& adjust = {},
                             bool realtime = false,
                             const std::function<cv::Mat(size_t, const cv::Mat&)>& edit_mask = {}) {
  const io::Sequence sequence = io::ReadDataset(folder);
  SystemOptions options;
  options.sensor = sequence.sensor;
  options.settings = io::LoadOrbSlamSettings(settings_path, sequence.sensor);
  options.deterministic = deterministic;
  if (adjust) adjust(&options);
  DatasetRun run;
  std::vector<double> total_ms, cpu_ms;
  {
    System system(options);
    const size_t n =
        max_frames > 0 ? std::min<size_t>(max_frames, sequence.size()) : sequence.size();
    const auto start = std::chrono::steady_clock::now();
    for (size_t i = 0; i < n; ++i) {
      const io::FrameEntry& entry = sequence.frames[i];
      if (realtime) {
        const double offset_s = entry.timestamp - sequence.frames[0].timestamp;
        std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                  std::chrono::duration<double>(offset_s)));
      }
      FrameInput input = LoadFrameInput(entry, options, mask_folder);
      if (edit_mask) input.mask = edit_mask(i, input.mask);
      const double cpu0 = ThreadCpuMs();
      run.reports.push_back(system.Track(input));
      cpu_ms.push_back(ThreadCpuMs() - cpu0);
      if (run.reports.back().state == TrackingState::kOk) ++run.frames_ok;
      total_ms.push_back(run.reports.back().times.total_ms);
    }
    system.Finish();
    run.estimate = system.CameraTrajectory();
    run.keyframes = system.KeyFrameTrajectory();
    run.summary = system.Summary();
  }
  run.track_ms_median = eval::Median(total_ms);
  run.track_cpu_ms_median = eval::Median(cpu_ms);
  if (sequence.ground_truth_path && run.estimate.size() >= 3) {
    eval::Trajectory gt = eval::ReadTrajectory(*sequence.ground_truth_path);
    if (!gt.has_timestamps()) {
      // KITTI poses carry no stamps: pose k belongs to frame k.
      gt.poses.resize(std::min(gt.poses.size(), sequence.size()));
      if (!gt.raw_rotations.empty()) gt.raw_rotations.resize(gt.poses.size());
      for (size_t k = 0; k < gt.poses.size(); ++k) {
        gt.timestamps.push_back(sequence.frames[k].timestamp);
      }
    }
    eval::AteOptions ate_options = eval::AteOptions::Defaults(eval::Convention::kTum);
    if (options.sensor == io::SensorType::kMonocular) {
      ate_options.alignment = eval::AlignmentMode::kSim3;
    }
    run.ate_rmse = eval::ComputeAte(gt, run.estimate, ate_options).translation.stats.rmse;
    eval::AteOptions sim3_options = ate_options;
    sim3_options.alignment = eval::AlignmentMode::kSim3;
    run.sim3_scale = eval::ComputeAte(gt, run.estimate, sim3_options).alignment.scale();
    if (run.keyframes.size() >= 3) {
      run.keyframe_ate_rmse =
          eval::ComputeAte(gt, run.keyframes, ate_options).translation.stats.rmse;
    }
  }
  return run;
}

}  // namespace moslam::slam
