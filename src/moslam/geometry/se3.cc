#include "moslam/geometry/se3.h"

#include "moslam/util/check.h"

namespace moslam::geometry {

SE3::SE3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) : q_(q), t_(t) {
  const double n = q.norm();
  MOSLAM_CHECK(n > 1e-12 && std::isfinite(n)) << "SE3 from a zero or non-finite quaternion";
  q_.coeffs() /= n;
}

SE3::SE3(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) : q_(R), t_(t) {
  MOSLAM_CHECK((R * R.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-6 &&
               R.determinant() > 0)
      << "SE3 from a matrix that is not a rotation:\n"
      << R;
  q_.normalize();
}

SE3 SE3::FromMatrix3x4(const Matrix3x4d& m) {
  return SE3(Eigen::Quaterniond(NearestRotation(m.leftCols<3>())), m.col(3));
}

SE3 SE3::Exp(const Vector6d& xi) {
  const Eigen::Vector3d rho = xi.head<3>();
  const Eigen::Vector3d phi = xi.tail<3>();
  return SE3(ExpSO3(phi), LeftJacobianSO3(phi) * rho);
}

Vector6d SE3::Log() const {
  const Eigen::Vector3d phi = LogSO3(q_);
  Vector6d xi;
  xi << LeftJacobianInverseSO3(phi) * t_, phi;
  return xi;
}

Eigen::Matrix4d SE3::Matrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = rotation_matrix();
  m.topRightCorner<3, 1>() = t_;
  return m;
}

Matrix3x4d SE3::Matrix3x4() const { return Matrix().topRows<3>(); }

SE3 SE3::Inverse() const {
  const Eigen::Quaterniond qi = q_.conjugate();
  return SE3(qi, -(qi * t_));
}

SE3 SE3::operator*(const SE3& o) const { return SE3(q_ * o.q_, q_ * o.t_ + t_); }

SE3 SE3::Interpolate(const SE3& a, const SE3& b, double s) {
  return a * Exp(s * (a.Inverse() * b).Log());
}

}  // namespace moslam::geometry
