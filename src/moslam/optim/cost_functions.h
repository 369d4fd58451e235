// Ceres pieces shared by the pose optimizer and the bundle adjuster: the SE(3) pose manifold and
// the monocular / stereo reprojection residuals with analytic Jacobians.
//
// Pose parameter block (7 doubles): [qx, qy, qz, qw, tx, ty, tz], the unit quaternion in Eigen's
// coefficient order followed by the translation of T_cam_world.
//
// Why the Jacobians are written the way they are ("tangent Jacobian" construction, the same idea
// as g2o's VertexSE3Expmap that ORB-SLAM2 uses): Ceres multiplies a cost function's Jacobian with
// respect to the 7 ambient parameters by the manifold's PlusJacobian (7x6) to get the Jacobian
// with respect to the 6 tangent parameters, and only that product enters the solver. The cost
// functions here store d r / d xi (the derivative along the left perturbation Exp(xi) * T, xi =
// [rho; phi] as in geometry/so3.h) in the first 6 columns and zero in the 7th, and the manifold's
// PlusJacobian is [I_6; 0], so the product is exactly d r / d xi. Neither factor alone is the
// derivative with respect to raw quaternion coefficients, which is never needed (and skipping it
// saves a 2x7 by 7x6 product per residual); tests check the product against central differences
// taken through SE3LeftManifold::Plus. Tools that use the ambient Jacobian alone
// (ceres::GradientChecker) do not apply to these cost functions.
#pragma once

#include <cmath>

#include <ceres/ceres.h>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"
#include "moslam/optim/observation.h"

namespace moslam::optim {

inline constexpr int kPoseSize = 7;     // ambient parameters of a pose block
inline constexpr int kPoseTangent = 6;  // its tangent dimension

// Points closer than this in front of the camera (metres) cannot be projected; such an
// observation is an outlier, and an optimizer step that moves a point there is rejected.
inline constexpr double kMinDepth = 1e-6;

void PackPose(const geometry::SE3& T, double* pose7);
geometry::SE3 UnpackPose(const double* pose7);

// SE(3) with the left update Plus(T, xi) = Exp(xi) * T and Minus(Y, X) = Log(Y * X^-1). See the
// file comment for why PlusJacobian is [I_6; 0] and MinusJacobian is [I_6, 0].
class SE3LeftManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kPoseSize; }
  int TangentSize() const override { return kPoseTangent; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool RightMultiplyByPlusJacobian(const double* x, int num_rows, const double* ambient_matrix,
                                   double* tangent_matrix) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// The whitened squared error (chi-square) of an observation of the camera-frame point p_cam, or
// +infinity when p_cam is not at least kMinDepth in front of the camera.
double ChiSquare(const CameraModel& camera, const Observation& observation,
                 const Eigen::Vector3d& p_cam);

// The chi-square threshold that applies to an observation.
inline double Chi2Threshold(const Observation& observation, double chi2_mono, double chi2_stereo) {
  return observation.is_stereo() ? chi2_stereo : chi2_mono;
}

namespace internal {

// Whitened residual [u, v(, u_right)] - observation of the camera-frame point p_cam and, when
// `jacobian` is not null, its derivative with respect to p_cam. False when the point is not in
// front of the camera.
template <int N>
bool ProjectionResidual(const CameraModel& camera, const Observation& observation, double sqrt_info,
                        const Eigen::Vector3d& p_cam, double* residual,
                        Eigen::Matrix<double, N, 3>* jacobian) {
  const double z = p_cam.z();
  if (!(z >= kMinDepth)) return false;
  const double inv_z = 1.0 / z;
  const double x = p_cam.x() * inv_z;
  const double y = p_cam.y() * inv_z;
  const double u = camera.fx * x + camera.cx;
  residual[0] = sqrt_info * (u - observation.pixel.x());
  residual[1] = sqrt_info * (camera.fy * y + camera.cy - observation.pixel.y());
  if constexpr (N == 3) {
    residual[2] = sqrt_info * std::sqrt(observation.right_info_scale) *
                  (u - camera.bf * inv_z - observation.u_right);
  }
  if (jacobian != nullptr) {
    const double s = sqrt_info * inv_z;
    auto& J = *jacobian;
    J(0, 0) = s * camera.fx;
    J(0, 1) = 0.0;
    J(0, 2) = -s * camera.fx * x;
    J(1, 0) = 0.0;
    J(1, 1) = s * camera.fy;
    J(1, 2) = -s * camera.fy * y;
    if constexpr (N == 3) {
      // u_right = u - bf / z: d/dz adds bf / z^2.
      const double s_right = s * std::sqrt(observation.right_info_scale);
      J(2, 0) = s_right * camera.fx;
      J(2, 1) = 0.0;
      J(2, 2) = s_right * (camera.bf * inv_z - camera.fx * x);
    }
  }
  return true;
}

// d p_cam / d xi for p_cam' = Exp(xi) * p_cam at xi = 0 is [I, -Hat(p_cam)], chained onto
// d r / d p_cam (TangentPoseJacobian; the Schur solver of schur_lm.h uses it as it is) and written
// into the 7 columns of a row-major pose Jacobian block, 7th = 0 (WritePoseJacobian).
template <int N>
Eigen::Matrix<double, N, kPoseTangent> TangentPoseJacobian(const Eigen::Matrix<double, N, 3>& J_p,
                                                           const Eigen::Vector3d& p_cam) {
  Eigen::Matrix<double, N, kPoseTangent> J;
  J.template leftCols<3>() = J_p;
  J.template rightCols<3>() = J_p * -geometry::Hat(p_cam);
  return J;
}
template <int N>
void WritePoseJacobian(const Eigen::Matrix<double, N, 3>& J_p, const Eigen::Vector3d& p_cam,
                       double* jacobian) {
  Eigen::Map<Eigen::Matrix<double, N, kPoseSize, Eigen::RowMajor>> J(jacobian);
  J.template leftCols<kPoseTangent>() = TangentPoseJacobian<N>(J_p, p_cam);
  J.col(6).setZero();
}

}  // namespace internal

// Reprojection residual of a fixed world point in a pose block (pose-only optimization).
// N = 2: monocular [u, v]; N = 3: stereo [u, v, u_right].
template <int N>
class PoseReprojectionCost final : public ceres::SizedCostFunction<N, kPoseSize> {
 public:
  PoseReprojectionCost(const CameraModel& camera, const Observation& observation,
                       const Eigen::Vector3d& p_world)
      : camera_(camera),
        observation_(observation),
        sqrt_info_(std::sqrt(observation.inv_sigma2)),
        p_world_(p_world) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Eigen::Quaterniond> q(parameters[0]);
    const Eigen::Map<const Eigen::Vector3d> t(parameters[0] + 4);
    const Eigen::Vector3d p_cam = q * p_world_ + t;
    const bool want_jacobian = jacobians != nullptr && jacobians[0] != nullptr;
    Eigen::Matrix<double, N, 3> J_p;
    if (!internal::ProjectionResidual<N>(camera_, observation_, sqrt_info_, p_cam, residuals,
                                         want_jacobian ? &J_p : nullptr)) {
      return false;
    }
    if (want_jacobian) internal::WritePoseJacobian<N>(J_p, p_cam, jacobians[0]);
    return true;
  }

 private:
  CameraModel camera_;
  Observation observation_;
  double sqrt_info_;
  Eigen::Vector3d p_world_;
};

// Reprojection residual of a point block (world coordinates, 3 doubles) in a pose block (bundle
// adjustment). N = 2: monocular; N = 3: stereo.
template <int N>
class BundleReprojectionCost final : public ceres::SizedCostFunction<N, kPoseSize, 3> {
 public:
  BundleReprojectionCost(const CameraModel& camera, const Observation& observation)
      : camera_(camera), observation_(observation), sqrt_info_(std::sqrt(observation.inv_sigma2)) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Eigen::Quaterniond> q(parameters[0]);
    const Eigen::Map<const Eigen::Vector3d> t(parameters[0] + 4);
    const Eigen::Map<const Eigen::Vector3d> p_world(parameters[1]);
    const Eigen::Vector3d p_cam = q * p_world + t;
    const bool want_pose = jacobians != nullptr && jacobians[0] != nullptr;
    const bool want_point = jacobians != nullptr && jacobians[1] != nullptr;
    Eigen::Matrix<double, N, 3> J_p;
    if (!internal::ProjectionResidual<N>(camera_, observation_, sqrt_info_, p_cam, residuals,
                                         want_pose || want_point ? &J_p : nullptr)) {
      return false;
    }
    if (want_pose) internal::WritePoseJacobian<N>(J_p, p_cam, jacobians[0]);
    if (want_point) {
      // d p_cam / d p_world = R_cam_world.
      Eigen::Map<Eigen::Matrix<double, N, 3, Eigen::RowMajor>> J(jacobians[1]);
      J = J_p * q.toRotationMatrix();
    }
    return true;
  }

 private:
  CameraModel camera_;
  Observation observation_;
  double sqrt_info_;
};

}  // namespace moslam::optim
