// The pinhole camera with radial-tangential distortion used by ORB-SLAM2 (and OpenCV).
//
// Pixel convention (OpenCV's): the centre of the top-left pixel is (0, 0), u grows to the right
// and v downwards; the camera frame has x right, y down, z forward (along the optical axis).
//
//   p_cam = (X, Y, Z) -> normalized (x, y) = (X/Z, Y/Z) -> distorted (x_d, y_d) (distortion.h)
//                     -> pixel (u, v) = (fx x_d + cx, fy y_d + cy)
//
// "Pinhole" functions skip the distortion step: they work on ideal (undistorted) pixels, the
// coordinates ORB-SLAM2 uses after undistorting its keypoints.
#pragma once

#include <optional>

#include <Eigen/Core>

#include "moslam/camera/distortion.h"

namespace moslam::camera {

struct PinholeOptions {
  double fx = 0.0;        // focal length along u, pixels (> 0)
  double fy = 0.0;        // focal length along v, pixels (> 0)
  double cx = 0.0;        // principal point u, pixels (inside the image when the size is known)
  double cy = 0.0;        // principal point v, pixels
  int width = 0;          // image width in pixels; 0 together with height = 0 means "unknown"
  int height = 0;         // image height in pixels
  Distortion distortion;  // all zero: an ideal pinhole (e.g. KITTI's rectified images)

  bool HasSize() const { return width > 0 && height > 0; }
  // Throws InputError naming the field (fx, fy, cx, cy, width, height, k1, ...) that is invalid:
  // non-finite values, focal lengths <= 0, negative or half-given sizes, or a principal point
  // outside a known image.
  void Check() const;
};

class PinholeCamera {
 public:
  // Throws InputError when options.Check() does.
  explicit PinholeCamera(const PinholeOptions& options);

  const PinholeOptions& options() const { return options_; }
  double fx() const { return options_.fx; }
  double fy() const { return options_.fy; }
  double cx() const { return options_.cx; }
  double cy() const { return options_.cy; }
  int width() const { return options_.width; }
  int height() const { return options_.height; }
  const Distortion& distortion() const { return options_.distortion; }
  bool HasDistortion() const { return !options_.distortion.IsZero(); }
  // The calibration matrix [fx 0 cx; 0 fy cy; 0 0 1].
  Eigen::Matrix3d K() const;

  // Camera-frame point -> observed (distorted) pixel. nullopt when the point is not in front of
  // the camera (Z <= 0) or not finite: such points have no image.
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p_cam) const;
  // Camera-frame point -> ideal pixel, ignoring distortion. nullopt as for Project.
  std::optional<Eigen::Vector2d> ProjectPinhole(const Eigen::Vector3d& p_cam) const;

  // Observed pixel -> ray (x, y, 1) in the camera frame, undistorting first: the point at depth Z
  // along the pixel's line of sight is Z * Unproject(px) (as for an RGB-D depth value).
  Eigen::Vector3d Unproject(const Eigen::Vector2d& px) const;
  // Observed pixel -> unit bearing vector in the camera frame.
  Eigen::Vector3d Bearing(const Eigen::Vector2d& px) const;
  // Ideal pixel -> ray (x, y, 1), no distortion.
  Eigen::Vector3d UnprojectPinhole(const Eigen::Vector2d& px) const;

  // Ideal pixel <-> normalized coordinates (no distortion).
  Eigen::Vector2d PixelToNormalized(const Eigen::Vector2d& px) const;
  Eigen::Vector2d NormalizedToPixel(const Eigen::Vector2d& normalized) const;
  // Observed pixel -> ideal pixel: cv::undistortPoints(..., K, D, noArray(), K) run to convergence.
  Eigen::Vector2d UndistortPixel(const Eigen::Vector2d& px) const;
  // Ideal pixel -> observed pixel.
  Eigen::Vector2d DistortPixel(const Eigen::Vector2d& px) const;

  // Whether border <= u < width - border and border <= v < height - border (the bounds ORB-SLAM2
  // uses for keypoints). Needs a known image size (CHECK).
  bool InImage(const Eigen::Vector2d& px, double border = 0.0) const;

 private:
  PinholeOptions options_;
};

}  // namespace moslam::camera
