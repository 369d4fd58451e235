#include "moslam/optim/cost_functions.h"

#include <limits>

namespace moslam::optim {

void PackPose(const geometry::SE3& T, double* pose7) {
  Eigen::Map<Eigen::Vector4d> q(pose7);
  Eigen::Map<Eigen::Vector3d> t(pose7 + 4);
  q = T.rotation().coeffs();
  t = T.translation();
}

geometry::SE3 UnpackPose(const double* pose7) {
  return geometry::SE3(Eigen::Quaterniond(Eigen::Map<const Eigen::Vector4d>(pose7)),
                       Eigen::Map<const Eigen::Vector3d>(pose7 + 4));
}

bool SE3LeftManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  PackPose(geometry::SE3::Exp(Eigen::Map<const geometry::Vector6d>(delta)) * UnpackPose(x),
           x_plus_delta);
  return true;
}

bool SE3LeftManifold::PlusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, kPoseSize, kPoseTangent, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.topRows<kPoseTangent>().setIdentity();
  return true;
}

bool SE3LeftManifold::RightMultiplyByPlusJacobian(const double* /*x*/, int num_rows,
                                                  const double* ambient_matrix,
                                                  double* tangent_matrix) const {
  // Multiplying by [I_6; 0] keeps the first 6 columns.
  using Ambient = Eigen::Matrix<double, Eigen::Dynamic, kPoseSize, Eigen::RowMajor>;
  using Tangent = Eigen::Matrix<double, Eigen::Dynamic, kPoseTangent, Eigen::RowMajor>;
  Eigen::Map<Tangent> tangent(tangent_matrix, num_rows, kPoseTangent);
  tangent = Eigen::Map<const Ambient>(ambient_matrix, num_rows, kPoseSize).leftCols<kPoseTangent>();
  return true;
}

bool SE3LeftManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  Eigen::Map<geometry::Vector6d> result(y_minus_x);
  result = (UnpackPose(y) * UnpackPose(x).Inverse()).Log();
  return true;
}

bool SE3LeftManifold::MinusJacobian(const double* /*x*/, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, kPoseTangent, kPoseSize, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.leftCols<kPoseTangent>().setIdentity();
  return true;
}

double ChiSquare(const CameraModel& camera, const Observation& observation,
                 const Eigen::Vector3d& p_cam) {
  const double sqrt_info = std::sqrt(observation.inv_sigma2);
  if (observation.is_stereo()) {
    Eigen::Vector3d r;
    if (!internal::ProjectionResidual<3>(camera, observation, sqrt_info, p_cam, r.data(),
                                         nullptr)) {
      return std::numeric_limits<double>::infinity();
    }
    return r.squaredNorm();
  }
  Eigen::Vector2d r;
  if (!internal::ProjectionResidual<2>(camera, observation, sqrt_info, p_cam, r.data(), nullptr)) {
    return std::numeric_limits<double>::infinity();
  }
  return r.squaredNorm();
}

}  // namespace moslam::optim
