// The analytic Jacobians of the reprojection residuals and of the pose manifold against central
// differences, and the manifold's own invariants.
#include "moslam/optim/cost_functions.h"

#include <random>

#include <ceres/manifold_test_utils.h>
#include <gtest/gtest.h>

#include "moslam/optim/synthetic.h"

namespace moslam::optim {
namespace {

// EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD names this type.
using Vector = Eigen::VectorXd;

struct Case {
  CameraModel camera;
  Observation observation;
  double pose[kPoseAmbientSize];
  Eigen::Vector3d point;
};

Case RandomCase(std::mt19937& rng, bool stereo) {
  Case c;
  c.camera = synthetic::StereoCamera();
  const geometry::SE3 T = synthetic::RandomPose(rng, 2.0, 1.0);
  PoseToParameters(T, c.pose);
  c.point = synthetic::PointInView(rng, c.camera, T, 1.0, 20.0);
  c.observation = synthetic::Observe(rng, c.camera, T, c.point, stereo, 3.0, false);
  c.observation.inv_sigma2 = 0.7;
  return c;
}

template <int kDim>
Eigen::Matrix<double, kDim, 1> Residual(const Case& c, const double* pose,
                                        const Eigen::Vector3d& point) {
  Eigen::Matrix<double, kDim, 1> r;
  EXPECT_TRUE(EvaluateReprojection<kDim>(c.camera, c.observation, pose, point.data(), r.data(),
                                         nullptr, nullptr));
  return r;
}

// d residual / d delta (tangent, through Plus) and d residual / d point, by central differences.
template <int kDim>
void CheckJacobians(const Case& c) {
  Eigen::Matrix<double, kDim, kPoseAmbientSize, Eigen::RowMajor> J_pose;
  Eigen::Matrix<double, kDim, 3, Eigen::RowMajor> J_point;
  Eigen::Matrix<double, kDim, 1> r;
  ASSERT_TRUE(EvaluateReprojection<kDim>(c.camera, c.observation, c.pose, c.point.data(), r.data(),
                                         J_pose.data(), J_point.data()));
  const PoseManifold manifold;
  Eigen::Matrix<double, kPoseAmbientSize, kPoseTangentSize, Eigen::RowMajor> plus_jacobian;
  ASSERT_TRUE(manifold.PlusJacobian(c.pose, plus_jacobian.data()));
  const Eigen::Matrix<double, kDim, 6> J_tangent = J_pose * plus_jacobian;

  const double h = 1e-6;
  Eigen::Matrix<double, kDim, 6> J_tangent_numeric;
  for (int k = 0; k < 6; ++k) {
    double delta[6] = {0, 0, 0, 0, 0, 0};
    double plus[kPoseAmbientSize], minus[kPoseAmbientSize];
    delta[k] = h;
    manifold.Plus(c.pose, delta, plus);
    delta[k] = -h;
    manifold.Plus(c.pose, delta, minus);
    J_tangent_numeric.col(k) =
        (Residual<kDim>(c, plus, c.point) - Residual<kDim>(c, minus, c.point)) / (2 * h);
  }
  // The ambient Jacobian itself, by differences of each of the 7 parameters (the quaternion is
  // perturbed off the unit sphere; the residual uses Eigen's q * p, defined for any q).
  Eigen::Matrix<double, kDim, kPoseAmbientSize> J_pose_numeric;
  for (int k = 0; k < kPoseAmbientSize; ++k) {
    double plus[kPoseAmbientSize], minus[kPoseAmbientSize];
    std::copy(c.pose, c.pose + kPoseAmbientSize, plus);
    std::copy(c.pose, c.pose + kPoseAmbientSize, minus);
    plus[k] += h;
    minus[k] -= h;
    J_pose_numeric.col(k) =
        (Residual<kDim>(c, plus, c.point) - Residual<kDim>(c, minus, c.point)) / (2 * h);
  }
  Eigen::Matrix<double, kDim, 3> J_point_numeric;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
    J_point_numeric.col(k) =
        (Residual<kDim>(c, c.pose, c.point + e) - Residual<kDim>(c, c.pose, c.point - e)) / (2 * h);
  }
  const auto near = [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
    return (a - b).cwiseAbs().maxCoeff() <= 1e-5 * std::max(1.0, b.cwiseAbs().maxCoeff());
  };
  EXPECT_TRUE(near(J_tangent, J_tangent_numeric)) << J_tangent << "\nvs\n" << J_tangent_numeric;
  EXPECT_TRUE(near(J_pose, J_pose_numeric)) << J_pose << "\nvs\n" << J_pose_numeric;
  EXPECT_TRUE(near(J_point, J_point_numeric)) << J_point << "\nvs\n" << J_point_numeric;
}

TEST(CostFunctions, MonoJacobiansMatchNumeric) {
  std::mt19937 rng(11);
  for (int i = 0; i < 20; ++i) CheckJacobians<2>(RandomCase(rng, false));
}

TEST(CostFunctions, StereoJacobiansMatchNumeric) {
  std::mt19937 rng(12);
  for (int i = 0; i < 20; ++i) CheckJacobians<3>(RandomCase(rng, true));
}

// The cost-function classes hand Ceres the numbers of EvaluateReprojection.
TEST(CostFunctions, ClassesEvaluateLikeTheFunction) {
  std::mt19937 rng(13);
  Case c = RandomCase(rng, true);
  const ReprojectionCost<3> ba(c.camera, c.observation);
  const PoseOnlyReprojectionCost<3> pose_only(c.camera, c.observation, c.point);
  const double* params[] = {c.pose, c.point.data()};
  Eigen::Vector3d r_ba, r_pose;
  Eigen::Matrix<double, 3, 7, Eigen::RowMajor> J_ba, J_pose;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> J_point;
  double* jac_ba[] = {J_ba.data(), J_point.data()};
  double* jac_pose[] = {J_pose.data()};
  ASSERT_TRUE(ba.Evaluate(params, r_ba.data(), jac_ba));
  ASSERT_TRUE(pose_only.Evaluate(params, r_pose.data(), jac_pose));
  EXPECT_EQ(r_ba, Residual<3>(c, c.pose, c.point));
  EXPECT_EQ(r_ba, r_pose);
  EXPECT_EQ(J_ba, J_pose);
}

TEST(CostFunctions, BehindCameraFailsToEvaluate) {
  std::mt19937 rng(14);
  Case c = RandomCase(rng, false);
  const geometry::SE3 T = PoseFromParameters(c.pose);
  const Eigen::Vector3d p_c = T * c.point;
  const Eigen::Vector3d behind = T.Inverse() * Eigen::Vector3d(p_c.x(), p_c.y(), -p_c.z());
  double r[2];
  EXPECT_FALSE(
      EvaluateReprojection<2>(c.camera, c.observation, c.pose, behind.data(), r, nullptr, nullptr));
  EXPECT_TRUE(std::isinf(CheckReprojection(c.camera, c.observation, T, behind).chi2));
}

TEST(CostFunctions, CheckReprojectionIsTheSquaredResidual) {
  std::mt19937 rng(15);
  for (const bool stereo : {false, true}) {
    Case c = RandomCase(rng, stereo);
    const ReprojectionCheck check =
        CheckReprojection(c.camera, c.observation, PoseFromParameters(c.pose), c.point);
    const double expected = stereo ? Residual<3>(c, c.pose, c.point).squaredNorm()
                                   : Residual<2>(c, c.pose, c.point).squaredNorm();
    EXPECT_NEAR(check.chi2, expected, 1e-9 * std::max(1.0, expected));
    EXPECT_GT(check.depth, 0.0);
  }
}

TEST(PoseManifold, PlusIsTheLeftUpdate) {
  std::mt19937 rng(16);
  const PoseManifold manifold;
  const geometry::SE3 T = synthetic::RandomPose(rng, 3.0, 2.0);
  geometry::Vector6d delta;
  delta << 0.1, -0.2, 0.3, 0.05, -0.1, 0.2;
  double x[kPoseAmbientSize], y[kPoseAmbientSize];
  PoseToParameters(T, x);
  manifold.Plus(x, delta.data(), y);
  const geometry::SE3 expected = geometry::SE3::Exp(delta) * T;
  EXPECT_LT((PoseFromParameters(y).Matrix() - expected.Matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

// The macro names Ceres's matchers unqualified.
using ceres::HasCorrectMinusJacobianAt, ceres::HasCorrectPlusJacobianAt,
    ceres::HasCorrectRightMultiplyByPlusJacobianAt, ceres::MinusPlusIsIdentityAt,
    ceres::MinusPlusJacobianIsIdentityAt, ceres::PlusMinusIsIdentityAt, ceres::XMinusXIsZeroAt,
    ceres::XPlusZeroIsXAt;

TEST(PoseManifold, SatisfiesCeresInvariants) {
  std::mt19937 rng(17);
  const PoseManifold manifold;
  for (int i = 0; i < 10; ++i) {
    double x[kPoseAmbientSize], y[kPoseAmbientSize];
    PoseToParameters(synthetic::RandomPose(rng, 3.0, 2.0), x);
    PoseToParameters(synthetic::RandomPose(rng, 3.0, 2.0), y);
    const Vector xv = Eigen::Map<const Vector>(x, kPoseAmbientSize);
    const Vector yv = Eigen::Map<const Vector>(y, kPoseAmbientSize);
    const Vector delta = 0.1 * Vector::Ones(kPoseTangentSize);
    EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD(manifold, xv, delta, yv, 1e-8);
  }
}

}  // namespace
}  // namespace moslam::optim
