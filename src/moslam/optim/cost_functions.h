// Ceres building blocks of the optimizers: the SE(3) pose manifold and the reprojection residuals
// with analytic Jacobians (checked against numeric differentiation in cost_functions_test.cc).
//
// Pose parameterization. A pose T_cam_world is a parameter block of 7 numbers
// [t (3); q (x, y, z, w)], Eigen's coefficient order. PoseManifold's Plus is the left update of
// geometry/so3.h, T' = Exp(delta) * T with delta = [rho; phi], so the tangent space is the one
// every other module uses. The cost functions return their true Jacobians with respect to these 7
// ambient numbers and PoseManifold::PlusJacobian is the true 7x6 derivative of Plus at delta = 0;
// Ceres multiplies the two. That costs one small product per residual more than the common trick
// of returning the 6-column tangent Jacobian padded to 7 columns with PlusJacobian = [I; 0], but
// the pieces then mean what Ceres documents, so ceres::GradientChecker, Problem::Evaluate and
// the manifold invariant tests all apply unchanged.
#pragma once

#include <ceres/manifold.h>
#include <ceres/sized_cost_function.h>

#include "moslam/geometry/se3.h"
#include "moslam/optim/observation.h"

namespace moslam::optim {

inline constexpr int kPoseAmbientSize = 7;
inline constexpr int kPoseTangentSize = 6;
// Points closer than this in front of the camera make a residual fail to evaluate (metres).
inline constexpr double kMinDepth = 1e-6;

void PoseToParameters(const geometry::SE3& T, double* x);
geometry::SE3 PoseFromParameters(const double* x);

class PoseManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kPoseAmbientSize; }
  int TangentSize() const override { return kPoseTangentSize; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  // Log(y * x^-1), the inverse of Plus.
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// The whitened residual sqrt(inv_sigma2) * (projection - measurement) of an observation of the
// world point p_w in the camera T_cam_world: [u, v] (kDim 2) or [u, v, u_right] (kDim 3) with
// u_right = u - bf / z. Optional Jacobians (row-major) w.r.t. the 7 pose parameters and p_w.
// Returns false when the point is not at least kMinDepth in front of the camera.
template <int kDim>
bool EvaluateReprojection(const CameraModel& camera, const Observation& observation,
                          const double* pose, const double* point_world, double* residuals,
                          double* jacobian_pose, double* jacobian_point);

// Pose and point both variable (bundle adjustment).
template <int kDim>
class ReprojectionCost final : public ceres::SizedCostFunction<kDim, kPoseAmbientSize, 3> {
 public:
  ReprojectionCost(const CameraModel& camera, const Observation& observation)
      : camera_(camera), observation_(observation) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    return EvaluateReprojection<kDim>(camera_, observation_, parameters[0], parameters[1],
                                      residuals, jacobians ? jacobians[0] : nullptr,
                                      jacobians ? jacobians[1] : nullptr);
  }

 private:
  CameraModel camera_;
  Observation observation_;
};

// Pose variable, point fixed (pose-only optimization).
template <int kDim>
class PoseOnlyReprojectionCost final : public ceres::SizedCostFunction<kDim, kPoseAmbientSize> {
 public:
  PoseOnlyReprojectionCost(const CameraModel& camera, const Observation& observation,
                           const Eigen::Vector3d& point_world)
      : camera_(camera), observation_(observation), point_world_(point_world) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    return EvaluateReprojection<kDim>(camera_, observation_, parameters[0], point_world_.data(),
                                      residuals, jacobians ? jacobians[0] : nullptr, nullptr);
  }

 private:
  CameraModel camera_;
  Observation observation_;
  Eigen::Vector3d point_world_;
};

// The chi-square error (squared whitened residual, stereo or mono by the observation) and the
// depth of the point in the camera; the optimizers' outlier test.
struct ReprojectionCheck {
  double chi2 = 0.0;
  double depth = 0.0;
};
ReprojectionCheck CheckReprojection(const CameraModel& camera, const Observation& observation,
                                    const geometry::SE3& T_cam_world,
                                    const Eigen::Vector3d& point_world);

}  // namespace moslam::optim
