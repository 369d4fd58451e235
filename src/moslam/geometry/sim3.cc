#include "moslam/geometry/sim3.h"

#include <cmath>

#include <unsupported/Eigen/MatrixFunctions>

#include "moslam/util/check.h"

namespace moslam::geometry {

Sim3::Sim3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t, double scale)
    : q_(q), t_(t), s_(scale) {
  const double n = q.norm();
  MOSLAM_CHECK(n > 1e-12 && std::isfinite(n)) << "Sim3 from a zero or non-finite quaternion";
  MOSLAM_CHECK(scale > 0 && std::isfinite(scale)) << "Sim3 scale must be positive, got " << scale;
  q_.coeffs() /= n;
}

// W = integral over u in [0, 1] of e^(sigma u) Exp(u phi) du. Its closed form has removable
// singularities at sigma = 0 and |phi| = 0 (Strasdat, "Local accuracy and global consistency
// for efficient visual SLAM", 2012, sec. 2.7); instead of special-casing each, W is read off
// the exponential of the block matrix [[A, I], [0, 0]] with A = sigma I + hat(phi), whose
// top-right block is exactly that integral. Eigen's Pade-based exp is accurate everywhere.
Eigen::Matrix3d Sim3TranslationJacobian(const Eigen::Vector3d& phi, double sigma) {
  Eigen::Matrix<double, 6, 6> m = Eigen::Matrix<double, 6, 6>::Zero();
  m.topLeftCorner<3, 3>() = sigma * Eigen::Matrix3d::Identity() + Hat(phi);
  m.topRightCorner<3, 3>() = Eigen::Matrix3d::Identity();
  const Eigen::Matrix<double, 6, 6> e = m.exp();
  return e.topRightCorner<3, 3>();
}

Sim3 Sim3::Exp(const Vector7d& xi) {
  const Eigen::Vector3d rho = xi.head<3>();
  const Eigen::Vector3d phi = xi.segment<3>(3);
  const double sigma = xi(6);
  return Sim3(ExpSO3(phi), Sim3TranslationJacobian(phi, sigma) * rho, std::exp(sigma));
}

Vector7d Sim3::Log() const {
  const Eigen::Vector3d phi = LogSO3(q_);
  const double sigma = std::log(s_);
  Vector7d xi;
  xi << Sim3TranslationJacobian(phi, sigma).partialPivLu().solve(t_), phi, sigma;
  return xi;
}

Eigen::Matrix4d Sim3::Matrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = s_ * rotation_matrix();
  m.topRightCorner<3, 1>() = t_;
  return m;
}

Sim3 Sim3::Inverse() const {
  const Eigen::Quaterniond qi = q_.conjugate();
  const double si = 1.0 / s_;
  return Sim3(qi, -si * (qi * t_), si);
}

Sim3 Sim3::operator*(const Sim3& o) const {
  return Sim3(q_ * o.q_, s_ * (q_ * o.t_) + t_, s_ * o.s_);
}

SE3 Sim3::operator*(const SE3& T) const {
  return SE3(q_ * T.rotation(), (*this) * T.translation());
}

Sim3 Sim3::Interpolate(const Sim3& a, const Sim3& b, double s) {
  return a * Exp(s * (a.Inverse() * b).Log());
}

}  // namespace moslam::geometry
