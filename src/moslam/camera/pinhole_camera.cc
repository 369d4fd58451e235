#include "moslam/camera/pinhole_camera.h"

#include <cmath>

#include <Eigen/Geometry>

#include "moslam/camera/camera_check.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::camera {

void PinholeOptions::Check() const { CheckPinholeOptions(*this, "camera "); }

PinholeCamera::PinholeCamera(const PinholeOptions& options) : options_(options) {
  options_.Check();
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx(), 0.0, cx(), 0.0, fy(), cy(), 0.0, 0.0, 1.0;
  return k;
}

std::optional<Eigen::Vector2d> PinholeCamera::Project(const Eigen::Vector3d& p_cam) const {
  if (!(p_cam.z() > 0.0) || !p_cam.allFinite()) return std::nullopt;
  const Eigen::Vector2d normalized = p_cam.head<2>() / p_cam.z();
  return NormalizedToPixel(Distort(options_.distortion, normalized));
}

std::optional<Eigen::Vector2d> PinholeCamera::ProjectPinhole(const Eigen::Vector3d& p_cam) const {
  if (!(p_cam.z() > 0.0) || !p_cam.allFinite()) return std::nullopt;
  return NormalizedToPixel(p_cam.head<2>() / p_cam.z());
}

Eigen::Vector3d PinholeCamera::Unproject(const Eigen::Vector2d& px) const {
  const Eigen::Vector2d normalized = Undistort(options_.distortion, PixelToNormalized(px));
  return normalized.homogeneous();
}

Eigen::Vector3d PinholeCamera::Bearing(const Eigen::Vector2d& px) const {
  return Unproject(px).normalized();
}

Eigen::Vector3d PinholeCamera::UnprojectPinhole(const Eigen::Vector2d& px) const {
  return PixelToNormalized(px).homogeneous();
}

Eigen::Vector2d PinholeCamera::PixelToNormalized(const Eigen::Vector2d& px) const {
  return {(px.x() - cx()) / fx(), (px.y() - cy()) / fy()};
}

Eigen::Vector2d PinholeCamera::NormalizedToPixel(const Eigen::Vector2d& normalized) const {
  return {fx() * normalized.x() + cx(), fy() * normalized.y() + cy()};
}

Eigen::Vector2d PinholeCamera::UndistortPixel(const Eigen::Vector2d& px) const {
  return NormalizedToPixel(Undistort(options_.distortion, PixelToNormalized(px)));
}

Eigen::Vector2d PinholeCamera::DistortPixel(const Eigen::Vector2d& px) const {
  return NormalizedToPixel(Distort(options_.distortion, PixelToNormalized(px)));
}

bool PinholeCamera::InImage(const Eigen::Vector2d& px, double border) const {
  MOSLAM_CHECK(options_.HasSize()) << "InImage needs the image size";
  return px.x() >= border && px.x() < width() - border && px.y() >= border &&
         px.y() < height() - border;
}

}  // namespace moslam::camera
