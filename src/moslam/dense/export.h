// `moslam map export RUN_DIR`: the dense map of a finished run (issue 27). The run's folder names
// its data set and settings (summary.json) and holds the keyframes' optimized poses
// (KeyFrameTrajectory.txt); each keyframe's depth (RGB-D: the depth image; stereo: semi-global
// matching of the pair) is fused at its pose (fusion.h) without the movable-object mask's pixels:
// the masks the run extracted its keyframes with (`moslam run --save-keyframe-masks`), or any
// mask source of `moslam run` (synth-gt, files DIR), or none. Writes map.bt (OctoMap), map.ply
// (coloured voxel centres), map_top.png (a view from above) and export.json (counts, timings and,
// for the synthetic generator's sequences, the scores of evaluation.h).
#pragma once

#include <optional>
#include <string>

#include "moslam/dense/cloud.h"
#include "moslam/dense/evaluation.h"
#include "moslam/dense/fusion.h"
#include "moslam/dense/stereo_depth.h"
#include "moslam/runner/mask_source.h"

namespace moslam::dense {

enum class ExportMasks {
  kRun,     // RUN_DIR/keyframe_masks/<stamp>.png (a keyframe without a file has no mask)
  kSource,  // ExportOptions::mask_source, as `moslam run --mask-source`
  kNone,    // fuse everything (to see what the masks remove)
};

struct ExportOptions {
  std::string run_dir;  // a `moslam run` output folder
  std::string out;      // empty: RUN_DIR/dense
  ExportMasks masks = ExportMasks::kRun;
  runner::MaskOptions mask_source;  // kSource
  DenseFusionOptions fusion;        // max_depth is replaced by the sensor's default unless set
  std::optional<double> max_depth;  // metres; default 4 (RGB-D), 30 (stereo)
  StereoDepthOptions stereo;
  RenderOptions render;
  // Against the synthetic generator's ground truth (groundtruth.txt, class/ and classes.txt):
  // the keyframes are first aligned to the ground truth (SE(3), Umeyama), so the map is in its
  // frame, and the scores go into export.json. InputError when the data set has no such truth.
  bool score = false;
  void Check() const;  // InputError naming the field
};

struct ExportResult {
  size_t keyframes = 0;      // fused
  size_t masked_frames = 0;  // of them with a mask
  InsertStats rays;          // summed over the keyframes
  size_t occupied = 0;
  double fusion_s = 0.0;  // fusing, without loading
  double total_s = 0.0;
  std::optional<DenseMapScores> scores;
  std::string octree, cloud, picture, report;  // the files written
};

ExportResult ExportDenseMap(const ExportOptions& options);

}  // namespace moslam::dense
