// The files `moslam run` leaves in its output folder, and its printed summary:
//
//   CameraTrajectory.txt        TUM `t tx ty tz qx qy qz qw`, every frame with a pose; ORB-SLAM2's
//                               SaveTrajectoryTUM precision (stamp 6 decimals, pose 9)
//   CameraTrajectory_kitti.txt  KITTI input only: the 3x4 T_world_cam row-major, 9 decimals
//                               (ORB-SLAM2's SaveTrajectoryKITTI); frames without a pose are absent
//   KeyFrameTrajectory.txt      TUM, keyframes; SaveKeyFrameTrajectoryTUM precision (6 / 7)
//   keyframe_graph.json         their covisibility edges, spanning tree and closed loops, as the
//                               viewer draws them (keyframe_graph.h); not for trackers without one
//   frames.csv                  one row per frame, kFramesCsvHeader's columns
//   summary.json                counts, per-stage time statistics, the per-frame breakdown
//                               (segmentation, CRF, extraction, tracking, mapping), settings, data
//                               set, mask source, the ATE when the data set has ground truth, how
//                               the run ended ("end": completed, failed or interrupted, and why)
//                               and the outputs that could not be written ("output_errors")
//   trajectory.png              ground truth against the aligned estimate (with ground truth only)
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "moslam/eval/ate.h"
#include "moslam/eval/trajectory.h"
#include "moslam/io/dataset.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/io/sequence.h"
#include "moslam/runner/run_loop.h"

namespace moslam::runner {

inline constexpr const char* kFramesCsvHeader =
    "index,timestamp,state,reason,features,matches,inliers,keyframe,extract_ms,track_ms,"
    "local_map_ms,keyframe_ms,total_ms,mask_ms,mask_fraction,seg_ms,crf_ms,relocalized,recovered,"
    "segmented,movable_mask_ms,movable_erased,moving_region_fraction,map_keyframes,map_points,"
    "rss_mb";

// Writers; InputError naming the file when it cannot be written.
void WriteOrbSlamTum(const eval::Trajectory& trajectory, int pose_decimals,
                     const std::string& path);
void WriteOrbSlamKitti(const eval::Trajectory& trajectory, const std::string& path);
void WriteFramesCsv(const RunResult& result, const std::string& path);

// What the run was, for summary.json and the printed summary.
struct RunDescription {
  std::string dataset_path;
  io::DatasetFormat format = io::DatasetFormat::kAuto;  // as read; kKitti adds the KITTI file
  std::string format_name;  // in place of io::ToString(format) when set ("video")
  io::SensorType sensor = io::SensorType::kStereo;
  std::string settings_path;
  io::OrbSlamSettings settings;
  std::string mask_source;          // MaskSource::Describe()
  std::string segment_every = "1";  // --segment-every: K or "auto"
  bool deterministic = false;
  int deterministic_mapping_frames = 1;   // SystemOptions::deterministic_mapping_frames
  double deterministic_mapping_ms = 0.0;  // SystemOptions::deterministic_mapping_ms_per_observation
  bool realtime = false;
};

// The ATE of the run against the data set's ground truth.
struct RunAte {
  eval::AteResult result;
  nlohmann::json json;  // eval::AteToJson
  std::string text;     // eval::FormatAteReport
};

// The data set's ground truth as EvaluateRun compares with it (with the stamps of <root>/times.txt
// when it has none); empty without one. InputError naming a broken file.
eval::Trajectory ReadGroundTruth(const io::Sequence& sequence);

// Reads sequence.ground_truth_path (and <root>/times.txt for a ground truth without stamps) as
// EvaluateRun will, so that a broken file fails before the run, not as a warning after it:
// InputError naming the file (and line). Does nothing without a ground truth.
void CheckGroundTruth(const io::Sequence& sequence);

// ATE of `camera_path` (the TUM file just written) against sequence.ground_truth_path, matched
// by timestamp: a ground truth without stamps (KITTI poses.txt) takes those of <root>/times.txt.
// Writes the trajectory plot to `plot_path` when it is not empty. nullopt, with a warning, when
// the sequence has no ground truth or too few poses associate.
std::optional<RunAte> EvaluateRun(const io::Sequence& sequence, const std::string& camera_path,
                                  const std::string& plot_path);

nlohmann::json SummaryJson(const RunResult& result, const RunDescription& description,
                           const std::optional<RunAte>& ate);
// The human summary printed on stdout.
std::string FormatSummary(const RunResult& result, const RunDescription& description,
                          const std::optional<RunAte>& ate);

// Creates `out_dir` and checks that a file can be written there, so that a run whose outputs
// cannot be kept fails before it starts: InputError naming the folder.
void CheckOutputFolder(const std::string& out_dir);

// Writes every output into `out_dir` (created if needed) and returns the printed summary.
// CameraTrajectory_kitti.txt is written for KITTI input (description.format) only. Each file is
// written whole or not at all (a temporary name, then a rename); a file that cannot be written
// (a full disk) leaves the others written, is listed in summary.json's "output_errors" and is
// thrown as an InputError at the end.
std::string WriteRunOutputs(const io::Sequence& sequence, const RunResult& result,
                            const RunDescription& description, const std::string& out_dir);

// numpy.percentile (linear interpolation) of `values` at `percent` in [0, 100]; 0 when empty.
double Percentile(std::vector<double> values, double percent);

}  // namespace moslam::runner
