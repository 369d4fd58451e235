// Radial-tangential lens distortion ("plumb bob"), the model of OpenCV's calibrateCamera and of
// ORB-SLAM2's Camera.k1, k2, p1, p2, k3 settings. It acts on normalized image coordinates
// (x, y) = (X/Z, Y/Z) of a point in the camera frame:
//
//   r2 = x^2 + y^2,   radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3
//   x_d = x radial + 2 p1 x y + p2 (r2 + 2 x^2)
//   y_d = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
//
// (Brown, "Decentering distortion of lenses", 1966; OpenCV documentation of calib3d.)
#pragma once

#include <array>

#include <Eigen/Core>

namespace moslam::camera {

struct Distortion {
  double k1 = 0.0;  // radial, r^2 term
  double k2 = 0.0;  // radial, r^4 term
  double p1 = 0.0;  // tangential
  double p2 = 0.0;  // tangential
  double k3 = 0.0;  // radial, r^6 term (optional in ORB-SLAM2 settings)

  bool IsZero() const { return k1 == 0.0 && k2 == 0.0 && p1 == 0.0 && p2 == 0.0 && k3 == 0.0; }
  // (k1, k2, p1, p2, k3): OpenCV's order for distCoeffs.
  std::array<double, 5> Coefficients() const { return {k1, k2, p1, p2, k3}; }
  // Throws InputError unless every coefficient is finite.
  void Check() const;
};

// Ideal normalized coordinates -> distorted normalized coordinates.
Eigen::Vector2d Distort(const Distortion& d, const Eigen::Vector2d& undistorted);
// d Distort / d (x, y) at `undistorted`.
Eigen::Matrix2d DistortJacobian(const Distortion& d, const Eigen::Vector2d& undistorted);

// Distorted normalized coordinates -> ideal normalized coordinates: the inverse of Distort.
//
// Runs the fixed-point iteration of OpenCV's undistortPoints (x <- (x_d - tangential(x)) /
// radial(x)), but to convergence (residual below 1e-12 in normalized units, about 1e-9 px)
// instead of OpenCV's default five iterations; when the fixed point contracts slowly (strong
// distortion near the image border) it finishes with Newton steps on Distort(x) = x_d. Outside
// the region where the model is invertible (radial factor <= 0) the best iterate is returned.
Eigen::Vector2d Undistort(const Distortion& d, const Eigen::Vector2d& distorted);

}  // namespace moslam::camera
