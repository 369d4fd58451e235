// The validation behind PinholeOptions::Check, with the field names prefixed so that a settings
// reader can name its own keys ("Camera." gives "Camera.fx"), and the bounds it uses.
#pragma once

#include <string>

#include "moslam/camera/pinhole_camera.h"

namespace moslam::camera {

// Focal lengths must lie in [kMinFocalPerSide, kMaxFocalPerSide] times the image's longer side
// when the size is known, in [kMinFocalPx, kMaxFocalPx] pixels when it is not. 0.01 sides is a
// horizontal field of view of 176 degrees, beyond what a pinhole model describes; 1000 sides is
// 0.06 degrees. Outside them the value is a typo (1e300, 1e-300, a lost decimal point) that
// overflows poses and projections further on.
constexpr double kMinFocalPerSide = 0.01;
constexpr double kMaxFocalPerSide = 1000.0;
constexpr double kMinFocalPx = 1.0;
constexpr double kMaxFocalPx = 1e6;
// The undistorted image must span at least this share of each side of the image.
constexpr double kMinUndistortedShare = 0.1;

// Throws InputError naming the field, `prefix` first ("camera fx", "Camera.fx"): non-finite
// values, negative or half-given sizes, a principal point outside a known image, focal lengths
// out of the range above, or (with a known size) a distortion CheckDistortionBounds refuses.
void CheckPinholeOptions(const PinholeOptions& options, const std::string& prefix);

// Throws InputError naming the five coefficients unless the distortion can be inverted over the
// whole image of options' known size: the undistorted positions of pixels along the borders and
// the centre lines must be finite and converged (re-distorting gives the pixel back) and grow
// with the pixel coordinates (where they stop growing the lens model folds the image over itself:
// two pixels would see one ray), and the undistorted image bounds must span at least
// kMinUndistortedShare of each side. The keypoint grid (feature::ComputeImageBounds) and every
// projection rely on this; absurd coefficients (k1 = -1e6, k3 = 1e300, p1 = 0.9) break it.
// Does nothing for a zero distortion; needs options.HasSize().
void CheckDistortionBounds(const PinholeOptions& options, const std::string& prefix);

}  // namespace moslam::camera
