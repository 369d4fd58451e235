// A rectified stereo pair as ORB-SLAM2 models it: both images share the left camera's pinhole
// intrinsics, and the right camera sits `baseline` metres along the left camera's +x axis, so a
// point at depth Z appears in the right image on the same row, shifted left by the disparity
// d = bf / Z pixels, where bf = baseline * fx (ORB-SLAM2's Camera.bf, in pixel-metres).
#pragma once

#include <optional>

#include <Eigen/Core>

#include "moslam/camera/pinhole_camera.h"

namespace moslam::camera {

// baseline (metres) = bf / fx. Throws InputError unless bf > 0 and fx > 0 are finite.
double BaselineFromBf(double bf, double fx);

class StereoCamera {
 public:
  // Throws InputError when the left options are invalid or bf is not a positive finite number.
  StereoCamera(const PinholeOptions& left, double bf);

  const PinholeCamera& left() const { return left_; }
  double bf() const { return bf_; }
  // Metres.
  double baseline() const { return bf_ / left_.fx(); }

  // Depth (metres) of a point with the given disparity u_left - u_right (pixels);
  // nullopt for disparities <= 0 (at or beyond infinity).
  std::optional<double> DepthFromDisparity(double disparity) const;
  // Disparity (pixels) of a point at depth (metres) > 0 (CHECK).
  double DisparityFromDepth(double depth) const;
  // Ideal (rectified) pixel of a left-camera-frame point in the right image; nullopt when the
  // point is not in front of the cameras.
  std::optional<Eigen::Vector2d> ProjectRight(const Eigen::Vector3d& p_left) const;

 private:
  PinholeCamera left_;
  double bf_;
};

}  // namespace moslam::camera
