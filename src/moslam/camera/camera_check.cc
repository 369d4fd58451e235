#include "moslam/camera/camera_check.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "moslam/camera/distortion.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::camera {
namespace {

void RequireFinite(const std::string& prefix, const char* name, double value) {
  if (!std::isfinite(value)) {
    ThrowInput("{}{} must be a finite number, got {}", prefix, name, value);
  }
}

void CheckFocalLength(const PinholeOptions& o, const std::string& prefix, const char* name,
                      double f) {
  if (!(f > 0.0)) {
    ThrowInput("{}{} must be a positive focal length in pixels, got {}", prefix, name, f);
  }
  if (o.HasSize()) {
    const double side = std::max(o.width, o.height);
    const double low = kMinFocalPerSide * side;
    const double high = kMaxFocalPerSide * side;
    if (f < low || f > high) {
      ThrowInput(
          "{}{} = {} px is not a focal length for a {}x{} image: it must be in [{}, {}] px ({} to "
          "{} times the longer side)",
          prefix, name, f, o.width, o.height, low, high, kMinFocalPerSide, kMaxFocalPerSide);
    }
  } else if (f < kMinFocalPx || f > kMaxFocalPx) {
    ThrowInput("{}{} = {} px is not a focal length: it must be in [{}, {}] px", prefix, name, f,
               kMinFocalPx, kMaxFocalPx);
  }
}

// Observed pixel -> ideal pixel and back, as PinholeCamera's (which checks its options when it is
// constructed, so it cannot serve the check itself).
Eigen::Vector2d UndistortPixel(const PinholeOptions& o, const Eigen::Vector2d& px) {
  const Eigen::Vector2d n =
      Undistort(o.distortion, Eigen::Vector2d((px.x() - o.cx) / o.fx, (px.y() - o.cy) / o.fy));
  return {o.fx * n.x() + o.cx, o.fy * n.y() + o.cy};
}

Eigen::Vector2d DistortPixel(const PinholeOptions& o, const Eigen::Vector2d& px) {
  const Eigen::Vector2d n =
      Distort(o.distortion, Eigen::Vector2d((px.x() - o.cx) / o.fx, (px.y() - o.cy) / o.fy));
  return {o.fx * n.x() + o.cx, o.fy * n.y() + o.cy};
}

// Undistorts kSamples + 1 pixels of one line across the image (`from` to `to`) and checks that
// each is finite and converged and that coordinate `axis` of the result strictly grows.
void CheckUndistortedLine(const PinholeOptions& o, const Eigen::Vector2d& from,
                          const Eigen::Vector2d& to, int axis, const std::string& what) {
  constexpr int kSamples = 32;
  // Undistort converges to 1e-12 normalized units; a residual of 0.01 px means it did not.
  constexpr double kMaxResidualPx = 0.01;
  double previous = -std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kSamples; ++i) {
    const Eigen::Vector2d px = from + (to - from) * (static_cast<double>(i) / kSamples);
    const Eigen::Vector2d ideal = UndistortPixel(o, px);
    if (!ideal.allFinite()) {
      ThrowInput("{}: pixel ({}, {}) has no finite undistorted position", what, px.x(), px.y());
    }
    if (!((DistortPixel(o, ideal) - px).norm() <= kMaxResidualPx)) {
      ThrowInput("{}: pixel ({}, {}) cannot be undistorted (the model has no inverse there)", what,
                 px.x(), px.y());
    }
    if (!(ideal[axis] > previous)) {
      ThrowInput("{}: the undistorted image folds over itself at pixel ({}, {})", what, px.x(),
                 px.y());
    }
    previous = ideal[axis];
  }
}

}  // namespace

void CheckDistortionBounds(const PinholeOptions& options, const std::string& prefix) {
  MOSLAM_CHECK(options.HasSize()) << "CheckDistortionBounds needs the image size";
  const Distortion& d = options.distortion;
  if (d.IsZero()) return;
  const std::string what = fmt::format(
      "{0}k1, {0}k2, {0}p1, {0}p2, {0}k3 = {1}, {2}, {3}, {4}, {5} cannot be the distortion of a "
      "{6}x{7} image",
      prefix, d.k1, d.k2, d.p1, d.p2, d.k3, options.width, options.height);
  const double w = options.width;
  const double h = options.height;
  for (const double v : {0.0, options.cy, h})
    CheckUndistortedLine(options, {0.0, v}, {w, v}, 0, what);
  for (const double u : {0.0, options.cx, w})
    CheckUndistortedLine(options, {u, 0.0}, {u, h}, 1, what);
  // The bounds feature::ComputeImageBounds gives the keypoint grid, from the four corners.
  const Eigen::Vector2d tl = UndistortPixel(options, {0.0, 0.0});
  const Eigen::Vector2d tr = UndistortPixel(options, {w, 0.0});
  const Eigen::Vector2d bl = UndistortPixel(options, {0.0, h});
  const Eigen::Vector2d br = UndistortPixel(options, {w, h});
  const double extent_x = std::max(tr.x(), br.x()) - std::min(tl.x(), bl.x());
  const double extent_y = std::max(bl.y(), br.y()) - std::min(tl.y(), tr.y());
  if (!(extent_x >= kMinUndistortedShare * w && extent_y >= kMinUndistortedShare * h)) {
    ThrowInput("{}: the undistorted image spans only {:.3g}x{:.3g} px", what, extent_x, extent_y);
  }
}

void CheckPinholeOptions(const PinholeOptions& o, const std::string& prefix) {
  RequireFinite(prefix, "fx", o.fx);
  RequireFinite(prefix, "fy", o.fy);
  RequireFinite(prefix, "cx", o.cx);
  RequireFinite(prefix, "cy", o.cy);
  if (o.width < 0 || o.height < 0) {
    ThrowInput("{0}width and {0}height must not be negative, got {1}x{2}", prefix, o.width,
               o.height);
  }
  if ((o.width == 0) != (o.height == 0)) {
    ThrowInput("{0}width and {0}height must both be given (or both be 0: unknown), got {1}x{2}",
               prefix, o.width, o.height);
  }
  CheckFocalLength(o, prefix, "fx", o.fx);
  CheckFocalLength(o, prefix, "fy", o.fy);
  if (o.HasSize()) {
    // The principal point of a real camera is near the image centre; outside the image it is a
    // sign of swapped or mistyped values (e.g. cx and cy exchanged for a portrait image).
    if (o.cx < 0.0 || o.cx >= o.width) {
      ThrowInput("{}cx = {} lies outside the image (width {})", prefix, o.cx, o.width);
    }
    if (o.cy < 0.0 || o.cy >= o.height) {
      ThrowInput("{}cy = {} lies outside the image (height {})", prefix, o.cy, o.height);
    }
  }
  const auto c = o.distortion.Coefficients();
  const char* names[] = {"k1", "k2", "p1", "p2", "k3"};
  for (int i = 0; i < 5; ++i) RequireFinite(prefix, names[i], c[i]);
  // Without a size there is no image to check the distortion over; `moslam run` requires the
  // images to have the settings' size when they give one (runner::RunOptions::image_size).
  if (o.HasSize()) CheckDistortionBounds(o, prefix);
}

}  // namespace moslam::camera
