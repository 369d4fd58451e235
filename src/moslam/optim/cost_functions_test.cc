// The analytic Jacobians of the reprojection residuals against central differences taken through
// the pose manifold's Plus (the tangent Jacobian Ceres actually uses: J_ambient * PlusJacobian).
#include "moslam/optim/cost_functions.h"

#include <array>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "moslam/geometry/test_util.h"
#include "moslam/optim/test_scene.h"

namespace moslam::optim {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
constexpr double kStep = 1e-6;

Eigen::VectorXd Residual(const ceres::CostFunction& cost,
                         const std::vector<const double*>& blocks) {
  Eigen::VectorXd r(cost.num_residuals());
  EXPECT_TRUE(cost.Evaluate(blocks.data(), r.data(), nullptr));
  return r;
}

// Analytic Jacobians: block 0 (pose) mapped to the tangent space through PlusJacobian, block 1
// (point, if any) as is.
std::vector<RowMatrix> AnalyticJacobians(const ceres::CostFunction& cost,
                                         const std::vector<const double*>& blocks) {
  const int m = cost.num_residuals();
  std::vector<RowMatrix> jacobians;
  for (int size : cost.parameter_block_sizes()) jacobians.emplace_back(m, size);
  std::vector<double*> pointers;
  for (RowMatrix& J : jacobians) pointers.push_back(J.data());
  Eigen::VectorXd r(m);
  EXPECT_TRUE(cost.Evaluate(blocks.data(), r.data(), pointers.data()));
  RowMatrix plus_jacobian(kPoseSize, kPoseTangent);
  SE3LeftManifold().PlusJacobian(blocks[0], plus_jacobian.data());
  jacobians[0] = RowMatrix(jacobians[0] * plus_jacobian);
  return jacobians;
}

// Central differences: the pose through SE3LeftManifold::Plus, the point coordinate-wise.
std::vector<RowMatrix> NumericJacobians(const ceres::CostFunction& cost,
                                        const std::vector<const double*>& blocks) {
  const int m = cost.num_residuals();
  const SE3LeftManifold manifold;
  std::vector<RowMatrix> result;
  RowMatrix J_pose(m, kPoseTangent);
  for (int k = 0; k < kPoseTangent; ++k) {
    std::array<double, kPoseSize> plus, minus;
    geometry::Vector6d delta = geometry::Vector6d::Zero();
    delta[k] = kStep;
    manifold.Plus(blocks[0], delta.data(), plus.data());
    delta[k] = -kStep;
    manifold.Plus(blocks[0], delta.data(), minus.data());
    std::vector<const double*> b_plus = blocks, b_minus = blocks;
    b_plus[0] = plus.data();
    b_minus[0] = minus.data();
    J_pose.col(k) = (Residual(cost, b_plus) - Residual(cost, b_minus)) / (2 * kStep);
  }
  result.push_back(J_pose);
  if (blocks.size() > 1) {
    RowMatrix J_point(m, 3);
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d plus = Eigen::Map<const Eigen::Vector3d>(blocks[1]);
      Eigen::Vector3d minus = plus;
      plus[k] += kStep;
      minus[k] -= kStep;
      J_point.col(k) =
          (Residual(cost, {blocks[0], plus.data()}) - Residual(cost, {blocks[0], minus.data()})) /
          (2 * kStep);
    }
    result.push_back(J_point);
  }
  return result;
}

void ExpectJacobiansMatch(const ceres::CostFunction& cost,
                          const std::vector<const double*>& blocks) {
  const std::vector<RowMatrix> analytic = AnalyticJacobians(cost, blocks);
  const std::vector<RowMatrix> numeric = NumericJacobians(cost, blocks);
  ASSERT_EQ(analytic.size(), numeric.size());
  for (size_t b = 0; b < analytic.size(); ++b) {
    // Relative to the Jacobian's scale (pixels per metre or per radian reach the hundreds).
    const double scale = std::max(1.0, numeric[b].cwiseAbs().maxCoeff());
    EXPECT_TRUE(geometry::test::MatricesNear(analytic[b], numeric[b], 1e-6 * scale))
        << "block " << b;
  }
}

struct Case {
  std::array<double, kPoseSize> pose;
  Eigen::Vector3d p_world;
  Observation observation;
};

// A random pose, a point in view at 0.5-20 m, a noisy observation of it at a random level.
Case RandomCase(std::mt19937& rng, bool stereo) {
  const CameraModel camera = test::TestCamera();
  Case c;
  const geometry::SE3 T = test::RandomPose(rng);
  PackPose(T, c.pose.data());
  const Eigen::Vector3d p_cam = test::RandomPointInView(rng, camera, 0.5, 20.0);
  c.p_world = T.Inverse() * p_cam;
  c.observation = test::NoisyObservation(rng, camera, p_cam, stereo);
  return c;
}

TEST(CostFunctions, MonoPoseJacobianMatchesNumeric) {
  std::mt19937 rng(1);
  for (int i = 0; i < 20; ++i) {
    const Case c = RandomCase(rng, false);
    const PoseReprojectionCost<2> cost(test::TestCamera(), c.observation, c.p_world);
    ExpectJacobiansMatch(cost, {c.pose.data()});
  }
}

TEST(CostFunctions, StereoPoseJacobianMatchesNumeric) {
  std::mt19937 rng(2);
  for (int i = 0; i < 20; ++i) {
    const Case c = RandomCase(rng, true);
    const PoseReprojectionCost<3> cost(test::TestCamera(), c.observation, c.p_world);
    ExpectJacobiansMatch(cost, {c.pose.data()});
  }
}

TEST(CostFunctions, MonoBundleJacobiansMatchNumeric) {
  std::mt19937 rng(3);
  for (int i = 0; i < 20; ++i) {
    const Case c = RandomCase(rng, false);
    const BundleReprojectionCost<2> cost(test::TestCamera(), c.observation);
    ExpectJacobiansMatch(cost, {c.pose.data(), c.p_world.data()});
  }
}

TEST(CostFunctions, StereoBundleJacobiansMatchNumeric) {
  std::mt19937 rng(4);
  for (int i = 0; i < 20; ++i) {
    const Case c = RandomCase(rng, true);
    const BundleReprojectionCost<3> cost(test::TestCamera(), c.observation);
    ExpectJacobiansMatch(cost, {c.pose.data(), c.p_world.data()});
  }
}

// The residual tests' point, 4 m in front of an identity pose, and an observation of it 1 px
// right and 2 px down of its projection with u_right 3 px right of its own.
Eigen::Vector3d ResidualPoint() { return Eigen::Vector3d(0.4, -0.2, 4.0); }
Observation OffsetObservation(const CameraModel& camera) {
  const Eigen::Vector3d ideal = test::Project(camera, ResidualPoint());
  Observation observation;
  observation.pixel = ideal.head<2>() + Eigen::Vector2d(1.0, -2.0);
  observation.u_right = ideal.z() + 3.0;
  return observation;
}

// The stereo residual of `observation` of ResidualPoint() at the identity pose.
Eigen::Vector3d StereoResidual(const CameraModel& camera, const Observation& observation) {
  std::array<double, kPoseSize> pose;
  PackPose(geometry::SE3(), pose.data());
  const double* blocks[] = {pose.data()};
  Eigen::Vector3d r = Eigen::Vector3d::Constant(std::nan(""));
  EXPECT_TRUE(PoseReprojectionCost<3>(camera, observation, ResidualPoint())
                  .Evaluate(blocks, r.data(), nullptr));
  return r;
}

TEST(CostFunctions, ResidualIsWhitenedReprojectionError) {
  const CameraModel camera = test::TestCamera();
  Observation observation = OffsetObservation(camera);
  observation.inv_sigma2 = 0.25;  // sigma 2 px
  const Eigen::Vector3d r = StereoResidual(camera, observation);
  EXPECT_TRUE(geometry::test::MatricesNear(r, Eigen::Vector3d(-0.5, 1.0, -1.5), 1e-12));
  EXPECT_NEAR(ChiSquare(camera, observation, ResidualPoint()), r.squaredNorm(), 1e-12);
  observation.u_right = -1.0;
  EXPECT_NEAR(ChiSquare(camera, observation, ResidualPoint()), 1.25, 1e-12);
}

// A far stereo row with a scaled information (FarStereoWeighting, issue 29): its residual and
// its Jacobian rows both carry the square root of the scale.
TEST(CostFunctions, ScaledRightRowJacobiansMatchNumeric) {
  std::mt19937 rng(5);
  for (int i = 0; i < 20; ++i) {
    Case c = RandomCase(rng, true);
    c.observation.right_info_scale = 0.05 + 0.9 * (i / 19.0);
    ExpectJacobiansMatch(PoseReprojectionCost<3>(test::TestCamera(), c.observation, c.p_world),
                         {c.pose.data()});
    ExpectJacobiansMatch(BundleReprojectionCost<3>(test::TestCamera(), c.observation),
                         {c.pose.data(), c.p_world.data()});
  }
}

TEST(CostFunctions, ScaledRightRowWeighsOnlyTheDisparity) {
  const CameraModel camera = test::TestCamera();
  Observation observation = OffsetObservation(camera);
  observation.right_info_scale = 0.25;
  const Eigen::Vector3d r = StereoResidual(camera, observation);
  // u and v rows at sigma 1 px; the u_right row's -3 px halved (sqrt(0.25)).
  EXPECT_TRUE(geometry::test::MatricesNear(r, Eigen::Vector3d(-1.0, 2.0, -1.5), 1e-12));
  EXPECT_NEAR(ChiSquare(camera, observation, ResidualPoint()), r.squaredNorm(), 1e-12);
}

TEST(FarStereoWeighting, WeighsOnlyStereoRowsBeyondTheCloseDepth) {
  const double bf = 40.0, close = 4.0;  // a disparity of 10 px is the close depth
  const auto with_disparity = [](double d) {
    Observation o;
    o.pixel = Eigen::Vector2d(300.0, 200.0);
    o.u_right = 300.0 - d;
    return o;
  };
  const FarStereoWeighting weighted{FarStereo::kDepthWeighted, close};
  EXPECT_TRUE(weighted.IsClose(bf, with_disparity(10.0)));
  EXPECT_FALSE(weighted.IsClose(bf, with_disparity(9.0)));
  EXPECT_FALSE(weighted.IsClose(bf, Observation()));
  Observation near = with_disparity(20.0);  // 2 m
  weighted.Apply(bf, 1.0, &near);
  EXPECT_EQ(near.right_info_scale, 1.0);
  EXPECT_EQ(near.u_right, 280.0);
  Observation far = with_disparity(5.0);  // 8 m: (4 / 8)^2
  weighted.Apply(bf, 1.0, &far);
  EXPECT_DOUBLE_EQ(far.right_info_scale, 0.25);
  EXPECT_EQ(far.u_right, 295.0);
  // Fewer close points to hold the scale: blended toward full weight, none without them.
  Observation half = with_disparity(5.0);
  weighted.Apply(bf, 0.5, &half);
  EXPECT_DOUBLE_EQ(half.right_info_scale, 0.5);
  Observation alone = with_disparity(5.0);
  weighted.Apply(bf, 0.0, &alone);
  EXPECT_EQ(alone.right_info_scale, 1.0);
  Observation at_infinity = with_disparity(0.0);  // no depth: nothing to weigh, dropped
  weighted.Apply(bf, 1.0, &at_infinity);
  EXPECT_FALSE(at_infinity.is_stereo());
  Observation mono;
  weighted.Apply(bf, 1.0, &mono);
  EXPECT_FALSE(mono.is_stereo());
  EXPECT_EQ(mono.right_info_scale, 1.0);

  Observation dropped = with_disparity(5.0);
  FarStereoWeighting{FarStereo::kMonocular, close}.Apply(bf, 0.0, &dropped);
  EXPECT_FALSE(dropped.is_stereo());
  Observation kept = with_disparity(5.0);
  FarStereoWeighting{FarStereo::kFull, close}.Apply(bf, 1.0, &kept);
  EXPECT_EQ(kept.u_right, 295.0);
  EXPECT_EQ(kept.right_info_scale, 1.0);
  Observation no_threshold = with_disparity(5.0);  // close depth 0: every depth is close
  FarStereoWeighting{FarStereo::kDepthWeighted, 0.0}.Apply(bf, 1.0, &no_threshold);
  EXPECT_EQ(no_threshold.right_info_scale, 1.0);
}

TEST(FarStereoWeighting, StrengthRisesFromFiftyToAHundredCloseObservationsPerPose) {
  EXPECT_EQ(FarStereoWeighting::Strength(0, 3), 0.0);
  EXPECT_EQ(FarStereoWeighting::Strength(150, 3), 0.0);  // 50 a pose
  EXPECT_DOUBLE_EQ(FarStereoWeighting::Strength(225, 3), 0.5);
  EXPECT_EQ(FarStereoWeighting::Strength(300, 3), 1.0);
  EXPECT_EQ(FarStereoWeighting::Strength(1000, 3), 1.0);
  EXPECT_EQ(FarStereoWeighting::Strength(10, 0), 0.0);
}

TEST(CostFunctions, PointBehindCameraFailsEvaluation) {
  const CameraModel camera = test::TestCamera();
  const Observation observation;
  std::array<double, kPoseSize> pose;
  PackPose(geometry::SE3(), pose.data());
  const double* blocks[] = {pose.data()};
  Eigen::Vector2d r = Eigen::Vector2d::Zero();
  EXPECT_FALSE(PoseReprojectionCost<2>(camera, observation, Eigen::Vector3d(0, 0, -1))
                   .Evaluate(blocks, r.data(), nullptr));
  EXPECT_TRUE(std::isinf(ChiSquare(camera, observation, Eigen::Vector3d(0, 0, -1))));
  EXPECT_TRUE(std::isinf(ChiSquare(camera, observation, Eigen::Vector3d(1, 0, 0))));
}

TEST(SE3LeftManifold, PlusIsLeftUpdateAndMinusInvertsIt) {
  std::mt19937 rng(5);
  const SE3LeftManifold manifold;
  for (int i = 0; i < 20; ++i) {
    const geometry::SE3 T = test::RandomPose(rng);
    const geometry::SE3 D = test::RandomPerturbation(rng, 0.3, 0.5);
    std::array<double, kPoseSize> x, y;
    PackPose(T, x.data());
    const geometry::Vector6d delta = D.Log();
    ASSERT_TRUE(manifold.Plus(x.data(), delta.data(), y.data()));
    EXPECT_TRUE(
        geometry::test::MatricesNear(UnpackPose(y.data()).Matrix(), (D * T).Matrix(), 1e-12));
    geometry::Vector6d back;
    ASSERT_TRUE(manifold.Minus(y.data(), x.data(), back.data()));
    EXPECT_TRUE(geometry::test::MatricesNear(back, delta, 1e-10));
  }
}

TEST(SE3LeftManifold, RightMultiplyMatchesPlusJacobian) {
  std::mt19937 rng(6);
  const SE3LeftManifold manifold;
  std::array<double, kPoseSize> x;
  PackPose(test::RandomPose(rng), x.data());
  const RowMatrix ambient = RowMatrix::Random(5, kPoseSize);
  RowMatrix plus_jacobian(kPoseSize, kPoseTangent), tangent(5, kPoseTangent);
  ASSERT_TRUE(manifold.PlusJacobian(x.data(), plus_jacobian.data()));
  ASSERT_TRUE(manifold.RightMultiplyByPlusJacobian(x.data(), 5, ambient.data(), tangent.data()));
  EXPECT_TRUE(geometry::test::MatricesNear(tangent, ambient * plus_jacobian, 0.0));
  RowMatrix minus_jacobian(kPoseTangent, kPoseSize);
  ASSERT_TRUE(manifold.MinusJacobian(x.data(), minus_jacobian.data()));
  EXPECT_TRUE(geometry::test::MatricesNear(minus_jacobian * plus_jacobian,
                                           RowMatrix::Identity(kPoseTangent, kPoseTangent), 0.0));
}

}  // namespace
}  // namespace moslam::optim
