// Disparity error of the sparse stereo matcher (feature/stereo_matcher.h) against the synthetic
// generator's exact depth (issue 29; docs/EVALUATION.md, "Stereo disparity bias"): shared by the
// stereo_bias tool and its test.
//
// Frames of a stereo preset are rendered in-process (with the sensor noise of written sequences
// unless told otherwise), ORB features (2000, 1.2, 8 levels as configs/KITTI04-12.yaml) are
// extracted in both images and matched with MatchStereo, and each match's disparity is compared
// with the truth bf / z. The truth is the inverse depth interpolated bilinearly (exact on planes)
// at the level-0 position of the keypoint's level pixel, (x_l + 0.5) * W / w_l - 0.5 (cv::resize's
// pixel centres), rounded to the pixel where the matcher centres its window when it refines on
// level 0. Matches whose SAD window touches sky or a depth edge (inverse depth not planar there)
// are flagged "edge": their error is the matcher's foreground fattening, not its sub-pixel step.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "moslam/feature/stereo_matcher.h"

namespace moslam::tools {

struct StereoSample {
  int octave = 0;
  double truth = 0.0;     // disparity, level-0 px
  double estimate = 0.0;  // disparity, level-0 px
  bool edge = false;      // the SAD window touches sky or a depth edge
  float x = 0, y = 0;     // where the truth was taken (level-0 px)
  int frame = 0;
};

struct StereoErrorOptions {
  std::string preset = "kitti_cars";  // a stereo preset
  uint64_t seed = 1;
  int frames = 20;  // frames 0, step, 2 step, ...
  int step = 10;
  bool noise = true;  // the colour noise of written sequences
  feature::StereoMatchOptions match;
};

struct StereoErrorResult {
  double bf = 0.0;  // pixel-metres
  std::vector<StereoSample> samples;
};

// Throws InputError for an unknown or non-stereo preset.
StereoErrorResult MeasureStereoError(const StereoErrorOptions& options);

// Statistics of the errors estimate - truth (level-0 px) of a set of samples. Errors beyond two
// level pixels (2 * 1.2^octave level-0 px) are mismatches (wrong descriptor match, repeated
// texture), counted as `gross`; the rest are summarised.
struct ErrorStats {
  int n = 0, gross = 0;
  double mean = 0, sd = 0, median = 0, mad = 0;  // px; mad is 1.4826 * median |e - median|
  double depth_mean = 0, depth_median = 0;       // z_est / z_true - 1
};
ErrorStats Summarise(const std::vector<const StereoSample*>& samples);

// Prints Summarise of `samples` as two Markdown tables, per octave and per true depth
// (`depth_bounds`: metres, ascending, starting at 0; the last bin is open), headed by
// "`title`, per octave" and "`title`, per true depth". `bf` converts disparities to depths.
void PrintErrorTables(const std::vector<const StereoSample*>& samples, const std::string& title,
                      double bf, const std::vector<double>& depth_bounds);

}  // namespace moslam::tools
