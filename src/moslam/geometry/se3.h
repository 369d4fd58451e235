// Rigid transforms SE(3): a unit quaternion and a translation. Frame convention: geometry/so3.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "moslam/geometry/so3.h"

namespace moslam::geometry {

class SE3 {
 public:
  SE3() : q_(Eigen::Quaterniond::Identity()), t_(Eigen::Vector3d::Zero()) {}
  // q is normalized; a zero quaternion is a broken invariant (CHECK).
  SE3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t);
  // R must be a rotation matrix (orthonormal, det +1) up to rounding.
  SE3(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);

  static SE3 Identity() { return SE3(); }
  // From the top 3x4 block of a homogeneous matrix; the rotation block is re-orthonormalized.
  static SE3 FromMatrix3x4(const Matrix3x4d& m);
  // xi = [rho; phi]: translation part rho (metres) first, rotation phi (radians) second.
  static SE3 Exp(const Vector6d& xi);
  Vector6d Log() const;

  const Eigen::Quaterniond& rotation() const { return q_; }
  Eigen::Matrix3d rotation_matrix() const { return q_.toRotationMatrix(); }
  const Eigen::Vector3d& translation() const { return t_; }
  Eigen::Matrix4d Matrix() const;
  Matrix3x4d Matrix3x4() const;

  SE3 Inverse() const;
  SE3 operator*(const SE3& other) const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return q_ * p + t_; }

  // The geodesic a * Exp(s * Log(a^-1 * b)); s = 0 gives a, s = 1 gives b.
  static SE3 Interpolate(const SE3& a, const SE3& b, double s);

 private:
  Eigen::Quaterniond q_;
  Eigen::Vector3d t_;
};

}  // namespace moslam::geometry
