#include "moslam/optim/cost_functions.h"

#include <cmath>
#include <limits>

#include "moslam/util/check.h"

namespace moslam::optim {
namespace {

using RowMajor7x6 = Eigen::Matrix<double, kPoseAmbientSize, kPoseTangentSize, Eigen::RowMajor>;
using RowMajor6x7 = Eigen::Matrix<double, kPoseTangentSize, kPoseAmbientSize, Eigen::RowMajor>;

// d(q * p) / d(q.x, q.y, q.z, q.w) for Eigen's q * p = p + 2w (v x p) + 2 v x (v x p), v = q.vec().
Eigen::Matrix<double, 3, 4> RotateJacobianWrtQuaternion(const Eigen::Quaterniond& q,
                                                        const Eigen::Vector3d& p) {
  const Eigen::Vector3d v = q.vec();
  Eigen::Matrix<double, 3, 4> J;
  J.leftCols<3>() =
      -2.0 * q.w() * geometry::Hat(p) +
      2.0 * (v.dot(p) * Eigen::Matrix3d::Identity() + v * p.transpose() - 2.0 * p * v.transpose());
  J.col(3) = 2.0 * v.cross(p);
  return J;
}

}  // namespace

void PoseToParameters(const geometry::SE3& T, double* x) {
  Eigen::Map<Eigen::Vector3d>{x} = T.translation();
  Eigen::Map<Eigen::Vector4d>{x + 3} = T.rotation().coeffs();
}

geometry::SE3 PoseFromParameters(const double* x) {
  return geometry::SE3(Eigen::Quaterniond(x[6], x[3], x[4], x[5]),
                       Eigen::Vector3d(x[0], x[1], x[2]));
}

bool PoseManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const geometry::SE3 T = PoseFromParameters(x);
  PoseToParameters(geometry::SE3::Exp(Eigen::Map<const geometry::Vector6d>(delta)) * T,
                   x_plus_delta);
  return true;
}

// Exp(delta) * T to first order: t' = t + rho + phi x t and q' = (1, phi / 2) (x) q.
bool PoseManifold::PlusJacobian(const double* x, double* jacobian) const {
  const Eigen::Map<const Eigen::Vector3d> t(x);
  const Eigen::Map<const Eigen::Quaterniond> q(x + 3);
  Eigen::Map<RowMajor7x6> J(jacobian);
  J.setZero();
  J.topLeftCorner<3, 3>().setIdentity();
  J.topRightCorner<3, 3>() = -geometry::Hat(t);
  J.block<3, 3>(3, 3) = 0.5 * (q.w() * Eigen::Matrix3d::Identity() - geometry::Hat(q.vec()));
  J.block<1, 3>(6, 3) = -0.5 * q.vec().transpose();
  return true;
}

bool PoseManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  Eigen::Map<geometry::Vector6d>{y_minus_x} =
      (PoseFromParameters(y) * PoseFromParameters(x).Inverse()).Log();
  return true;
}

// Log(y * x^-1) for y = x + dy to first order: phi = 2 vec(dq (x) q*), rho = dt + Hat(t) phi.
bool PoseManifold::MinusJacobian(const double* x, double* jacobian) const {
  const Eigen::Map<const Eigen::Vector3d> t(x);
  const Eigen::Map<const Eigen::Quaterniond> q(x + 3);
  Eigen::Matrix<double, 3, 4> dphi_dq;
  dphi_dq.leftCols<3>() = 2.0 * (q.w() * Eigen::Matrix3d::Identity() + geometry::Hat(q.vec()));
  dphi_dq.col(3) = -2.0 * q.vec();
  Eigen::Map<RowMajor6x7> J(jacobian);
  J.setZero();
  J.topLeftCorner<3, 3>().setIdentity();
  J.topRightCorner<3, 4>() = geometry::Hat(t) * dphi_dq;
  J.bottomRightCorner<3, 4>() = dphi_dq;
  return true;
}

template <int kDim>
bool EvaluateReprojection(const CameraModel& camera, const Observation& observation,
                          const double* pose, const double* point_world, double* residuals,
                          double* jacobian_pose, double* jacobian_point) {
  const Eigen::Map<const Eigen::Vector3d> t(pose);
  const Eigen::Map<const Eigen::Quaterniond> q(pose + 3);
  const Eigen::Map<const Eigen::Vector3d> p_w(point_world);
  const Eigen::Vector3d p_c = q * p_w + t;
  if (!(p_c.z() >= kMinDepth)) return false;
  const double inv_z = 1.0 / p_c.z();
  const double u = camera.fx * p_c.x() * inv_z + camera.cx;
  const double v = camera.fy * p_c.y() * inv_z + camera.cy;
  const double s = std::sqrt(observation.inv_sigma2);
  residuals[0] = s * (u - observation.pixel.x());
  residuals[1] = s * (v - observation.pixel.y());
  if constexpr (kDim == 3) residuals[2] = s * (u - camera.bf * inv_z - observation.u_right);
  if (jacobian_pose == nullptr && jacobian_point == nullptr) return true;

  // Whitened d residual / d p_c.
  const double inv_z2 = inv_z * inv_z;
  Eigen::Matrix<double, kDim, 3> J_pc;
  J_pc.row(0) << camera.fx * inv_z, 0.0, -camera.fx * p_c.x() * inv_z2;
  J_pc.row(1) << 0.0, camera.fy * inv_z, -camera.fy * p_c.y() * inv_z2;
  if constexpr (kDim == 3) {
    J_pc.row(2) << camera.fx * inv_z, 0.0, (camera.bf - camera.fx * p_c.x()) * inv_z2;
  }
  J_pc *= s;
  if (jacobian_pose != nullptr) {
    Eigen::Map<Eigen::Matrix<double, kDim, kPoseAmbientSize, Eigen::RowMajor>> J(jacobian_pose);
    J.template leftCols<3>() = J_pc;
    J.template rightCols<4>() = J_pc * RotateJacobianWrtQuaternion(q, p_w);
  }
  if (jacobian_point != nullptr) {
    Eigen::Map<Eigen::Matrix<double, kDim, 3, Eigen::RowMajor>> J(jacobian_point);
    J = J_pc * q.toRotationMatrix();
  }
  return true;
}

template bool EvaluateReprojection<2>(const CameraModel&, const Observation&, const double*,
                                      const double*, double*, double*, double*);
template bool EvaluateReprojection<3>(const CameraModel&, const Observation&, const double*,
                                      const double*, double*, double*, double*);

ReprojectionCheck CheckReprojection(const CameraModel& camera, const Observation& observation,
                                    const geometry::SE3& T_cam_world,
                                    const Eigen::Vector3d& point_world) {
  const Eigen::Vector3d p_c = T_cam_world * point_world;
  ReprojectionCheck check;
  check.depth = p_c.z();
  if (!(p_c.z() >= kMinDepth)) {
    check.chi2 = std::numeric_limits<double>::infinity();
    return check;
  }
  const double inv_z = 1.0 / p_c.z();
  const double u = camera.fx * p_c.x() * inv_z + camera.cx;
  const double v = camera.fy * p_c.y() * inv_z + camera.cy;
  const double du = u - observation.pixel.x();
  const double dv = v - observation.pixel.y();
  double e2 = du * du + dv * dv;
  if (observation.is_stereo()) {
    const double dr = u - camera.bf * inv_z - observation.u_right;
    e2 += dr * dr;
  }
  check.chi2 = observation.inv_sigma2 * e2;
  return check;
}

}  // namespace moslam::optim
