// Checks of a written synthetic sequence against its own ground truth: static pixels of frame i,
// lifted with the exact depth (depth_gt/, written with --exact-depth; else the noisy depth/) and
// moved with the ground-truth poses into frame j, must land on the same surface (same depth) and
// the same texture (same colour).
#pragma once

#include <string>

namespace moslam::synth {

struct ReprojectionStats {
  bool exact_depth = false;  // depth_gt/ was used (else the noisy depth/)
  long checked = 0;          // static pixels that land inside frame j on a static pixel
  long occluded = 0;  // of those, hidden in frame j (predicted depth behind the surface by > 5 cm)
  double depth_median = 0, depth_p90 = 0, depth_p99 = 0;  // |z_pred - z_gt_j|, metres
  double grey_median = 0, grey_p90 = 0;                   // |I_i - I_j|, grey levels
  // Fraction of checked pixels whose noisy depth (depth/) is within 3 sigma of the Kinect model
  // plus the disparity quantization step; holes are not counted.
  double noisy_within_3sigma = 0;
};

// Compares frame pairs (i, i + gap) for i = 0, step, 2 step, ... < frames - gap, sampling every
// `pixel_step`-th pixel. Throws InputError when the folder lacks the files.
ReprojectionStats CheckReprojection(const std::string& dir, int gap, int step, int pixel_step = 4);

}  // namespace moslam::synth
