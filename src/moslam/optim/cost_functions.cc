#include "moslam/optim/cost_functions.h"

#include <algorithm>
#include <cmath>
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

bool FarStereoWeighting::IsClose(double bf, const Observation& observation) const {
  if (!observation.is_stereo()) return false;
  const double disparity = observation.pixel.x() - observation.u_right;
  return disparity > 0.0 && (close_depth <= 0.0 || bf / disparity <= close_depth);
}

double FarStereoWeighting::Strength(size_t close, size_t poses) {
  if (poses == 0) return 0.0;
  const double per_pose = static_cast<double>(close) / static_cast<double>(poses);
  return std::clamp((per_pose - kCloseObservationsPerPoseNone) /
                        (kCloseObservationsPerPose - kCloseObservationsPerPoseNone),
                    0.0, 1.0);
}

void FarStereoWeighting::Apply(double bf, double strength, Observation* observation) const {
  if (policy == FarStereo::kFull || close_depth <= 0.0 || !observation->is_stereo()) return;
  const double disparity = observation->pixel.x() - observation->u_right;
  const double depth = disparity > 0.0 ? bf / disparity : std::numeric_limits<double>::infinity();
  if (!(depth > close_depth)) return;
  if (policy == FarStereo::kMonocular || !std::isfinite(depth)) {
    observation->u_right = -1.0;
    return;
  }
  const double ratio = close_depth / depth;
  observation->right_info_scale = std::max(ratio * ratio, 1.0 - std::clamp(strength, 0.0, 1.0));
}

}  // namespace moslam::optim
