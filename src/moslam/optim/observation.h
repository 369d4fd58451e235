// What the optimizers see of the map: a camera model and observations of 3D points, as plain
// data. The optim module knows nothing of KeyFrame/MapPoint; the slam module copies what it needs
// into these structs and writes the results back, so the problems can be built and tested alone.
#pragma once

#include <Eigen/Core>

namespace moslam::optim {

// Ideal pinhole (undistorted pixels, as feature::Frame::keypoints_undistorted) plus the stereo
// term: a point at depth Z has u_right = u - bf / Z (ORB-SLAM2's stereo/RGB-D observation).
struct CameraModel {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  // pixels
  double bf = 0.0;                                // baseline * fx (pixel-metres); 0 = monocular
};

// One observation of a point in a camera. `u_right < 0` makes it a monocular (2D) residual,
// otherwise a stereo (3D) residual [u, v, u_right]. The residual is whitened by
// sqrt(inv_sigma2) (ORB-SLAM2: 1 / scale_factor^(2*octave), the keypoint's pyramid level).
struct Observation {
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // undistorted pixel (u, v)
  double u_right = -1.0;                            // pixels; < 0: monocular
  double inv_sigma2 = 1.0;                          // 1 / pixel variance (> 0)

  bool is_stereo() const { return u_right >= 0.0; }
};

// ORB-SLAM2's chi-square thresholds at 95 %: 2 DoF (monocular) and 3 DoF (stereo).
inline constexpr double kChi2Mono = 5.991;
inline constexpr double kChi2Stereo = 7.815;

}  // namespace moslam::optim
