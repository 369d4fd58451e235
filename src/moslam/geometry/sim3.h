// Similarity transforms Sim(3): scale s > 0, rotation and translation; p' = s R p + t.
// Used for monocular maps (scale drift) and scale-correcting trajectory alignment.
// Frame convention: geometry/so3.h (S_a_b maps points from b into a).
#pragma once

#include "moslam/geometry/se3.h"

namespace moslam::geometry {

class Sim3 {
 public:
  Sim3() : q_(Eigen::Quaterniond::Identity()), t_(Eigen::Vector3d::Zero()), s_(1.0) {}
  // q is normalized; scale must be positive and finite (CHECK).
  Sim3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t, double scale);
  explicit Sim3(const SE3& T) : Sim3(T.rotation(), T.translation(), 1.0) {}

  static Sim3 Identity() { return Sim3(); }
  // xi = [rho; phi; sigma]: translation part, rotation (radians), log-scale (scale = e^sigma).
  static Sim3 Exp(const Vector7d& xi);
  Vector7d Log() const;

  const Eigen::Quaterniond& rotation() const { return q_; }
  Eigen::Matrix3d rotation_matrix() const { return q_.toRotationMatrix(); }
  const Eigen::Vector3d& translation() const { return t_; }
  double scale() const { return s_; }
  Eigen::Matrix4d Matrix() const;
  // The rigid part, with the scale dropped (what a pose is once the scale has been applied).
  SE3 ToSE3() const { return SE3(q_, t_); }

  Sim3 Inverse() const;
  Sim3 operator*(const Sim3& other) const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return s_ * (q_ * p) + t_; }
  // Applies this similarity to a camera pose T_b_cam (b is this transform's source frame):
  // rotation and position move with the similarity, the result is again a rigid T_a_cam.
  SE3 operator*(const SE3& T) const;

  // The geodesic a * Exp(s * Log(a^-1 * b)).
  static Sim3 Interpolate(const Sim3& a, const Sim3& b, double s);

 private:
  Eigen::Quaterniond q_;
  Eigen::Vector3d t_;
  double s_;
};

// The 3x3 matrix W with t = W rho in Sim(3)'s Exp; exposed for tests.
Eigen::Matrix3d Sim3TranslationJacobian(const Eigen::Vector3d& phi, double sigma);

}  // namespace moslam::geometry
