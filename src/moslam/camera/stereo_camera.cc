#include "moslam/camera/stereo_camera.h"

#include <cmath>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::camera {

double BaselineFromBf(double bf, double fx) {
  if (!std::isfinite(bf) || !(bf > 0.0)) {
    ThrowInput("stereo bf (baseline times fx) must be a positive number, got {}", bf);
  }
  if (!std::isfinite(fx) || !(fx > 0.0)) {
    ThrowInput("camera fx must be a positive focal length in pixels, got {}", fx);
  }
  return bf / fx;
}

StereoCamera::StereoCamera(const PinholeOptions& left, double bf) : left_(left), bf_(bf) {
  BaselineFromBf(bf, left.fx);  // validates bf
}

std::optional<double> StereoCamera::DepthFromDisparity(double disparity) const {
  if (!(disparity > 0.0) || !std::isfinite(disparity)) return std::nullopt;
  return bf_ / disparity;
}

double StereoCamera::DisparityFromDepth(double depth) const {
  MOSLAM_CHECK_GT(depth, 0.0);
  return bf_ / depth;
}

std::optional<Eigen::Vector2d> StereoCamera::ProjectRight(const Eigen::Vector3d& p_left) const {
  auto px = left_.ProjectPinhole(p_left);
  if (!px) return std::nullopt;
  px->x() -= bf_ / p_left.z();
  return px;
}

}  // namespace moslam::camera
