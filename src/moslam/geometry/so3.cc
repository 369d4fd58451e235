#include "moslam/geometry/so3.h"

#include <cmath>

#include <Eigen/SVD>

namespace moslam::geometry {
namespace {
// Below this angle the closed forms lose precision to cancellation; Taylor series take over.
constexpr double kSmallAngle = 1e-4;
}  // namespace

Eigen::Matrix3d Hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Vector3d Vee(const Eigen::Matrix3d& m) { return {m(2, 1), m(0, 2), m(1, 0)}; }

Eigen::Quaterniond ExpSO3(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const double half = 0.5 * theta;
  // sin(theta/2)/theta, with its series near zero.
  const double k = theta < kSmallAngle ? 0.5 - theta * theta / 48.0 : std::sin(half) / theta;
  return Eigen::Quaterniond(std::cos(half), k * omega.x(), k * omega.y(), k * omega.z());
}

Eigen::Vector3d LogSO3(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // same rotation, angle in [0, pi]
  const Eigen::Vector3d v = q.vec();
  const double n = v.norm();
  // theta = 2 atan2(|v|, w) is well conditioned everywhere, unlike acos(w).
  const double theta = 2.0 * std::atan2(n, q.w());
  if (n < 1e-12) return 2.0 * v / q.w();  // first order: theta ~ 2|v|/w
  return (theta / n) * v;
}

double RotationAngle(const Eigen::Quaterniond& q) {
  const Eigen::Quaterniond u = q.normalized();
  return 2.0 * std::atan2(u.vec().norm(), std::abs(u.w()));
}

Eigen::Matrix3d LeftJacobianSO3(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d W = Hat(phi);
  double a, b;  // J = I + a W + b W^2
  if (theta < kSmallAngle) {
    const double t2 = theta * theta;
    a = 0.5 - t2 / 24.0;
    b = 1.0 / 6.0 - t2 / 120.0;
  } else {
    const double t2 = theta * theta;
    a = (1.0 - std::cos(theta)) / t2;
    b = (theta - std::sin(theta)) / (t2 * theta);
  }
  return Eigen::Matrix3d::Identity() + a * W + b * W * W;
}

Eigen::Matrix3d LeftJacobianInverseSO3(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d W = Hat(phi);
  double b;  // J^-1 = I - W/2 + b W^2
  if (theta < kSmallAngle) {
    b = 1.0 / 12.0 + theta * theta / 720.0;
  } else {
    const double half = 0.5 * theta;
    b = (1.0 - half * std::cos(half) / std::sin(half)) / (theta * theta);
  }
  return Eigen::Matrix3d::Identity() - 0.5 * W + b * W * W;
}

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) d(2, 2) = -1;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

}  // namespace moslam::geometry
