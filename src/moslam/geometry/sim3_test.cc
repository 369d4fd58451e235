#include "moslam/geometry/sim3.h"

#include <random>

#include <gtest/gtest.h>

#include "moslam/geometry/test_util.h"

namespace moslam::geometry {
namespace {

using test::MatricesNear;

TEST(Sim3, GroupAxiomsAndMatrixProduct) {
  std::mt19937 rng(20);
  for (int i = 0; i < 30; ++i) {
    const Sim3 a = test::RandomSim3(rng), b = test::RandomSim3(rng), c = test::RandomSim3(rng);
    EXPECT_TRUE(MatricesNear(((a * b) * c).Matrix(), (a * (b * c)).Matrix(), 1e-10));
    EXPECT_TRUE(MatricesNear((a * a.Inverse()).Matrix(), Eigen::Matrix4d::Identity(), 1e-12));
    EXPECT_TRUE(MatricesNear((a * b).Matrix(), a.Matrix() * b.Matrix(), 1e-10));
    const Eigen::Vector3d p = test::RandomVector(rng, 2);
    EXPECT_TRUE(MatricesNear(a * p, (a.Matrix() * p.homogeneous()).head<3>(), 1e-12));
  }
}

TEST(Sim3, ExpLogRoundTripAcrossSingularCases) {
  std::mt19937 rng(21);
  // Zero rotation, zero log-scale, both, and generic values: the closed form of W has removable
  // singularities exactly there.
  for (double rot : {0.0, 1e-9, 1e-4, 1.0, 3.0}) {
    for (double sigma : {0.0, 1e-9, -1e-4, 0.7, -2.0}) {
      Vector7d xi;
      xi << test::RandomVector(rng, 2), test::RandomVector(rng, 1).normalized() * rot, sigma;
      EXPECT_TRUE(MatricesNear(Sim3::Exp(xi).Log(), xi, 1e-9))
          << "rotation " << rot << " sigma " << sigma;
    }
  }
}

TEST(Sim3, TranslationJacobianMatchesIntegralDefinition) {
  // W = integral_0^1 e^(sigma u) Exp(u phi) du, by the midpoint rule with many steps.
  const Eigen::Vector3d phi(0.3, -1.1, 0.4);
  const double sigma = 0.45;
  const int n = 20000;
  Eigen::Matrix3d integral = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    const double u = (i + 0.5) / n;
    integral += std::exp(sigma * u) * ExpSO3(u * phi).toRotationMatrix() / n;
  }
  EXPECT_TRUE(MatricesNear(Sim3TranslationJacobian(phi, sigma), integral, 1e-8));
  // With sigma = 0 it is SE(3)'s left Jacobian.
  EXPECT_TRUE(MatricesNear(Sim3TranslationJacobian(phi, 0), LeftJacobianSO3(phi), 1e-12));
}

TEST(Sim3, ActsOnPosesAndAgreesWithSE3WhenScaleIsOne) {
  std::mt19937 rng(22);
  const SE3 T = test::RandomSE3(rng), pose = test::RandomSE3(rng);
  const Sim3 S(T);
  EXPECT_TRUE(MatricesNear((S * pose).Matrix(), (T * pose).Matrix(), 1e-12));
  // A scaled similarity moves the pose's position by s R p + t and keeps it rigid.
  const Sim3 scaled(T.rotation(), T.translation(), 2.0);
  const SE3 moved = scaled * pose;
  EXPECT_TRUE(MatricesNear(moved.translation(), scaled * pose.translation(), 1e-12));
  EXPECT_TRUE(
      MatricesNear(moved.rotation_matrix(), T.rotation_matrix() * pose.rotation_matrix(), 1e-12));
}

TEST(Sim3, InterpolationEndpoints) {
  std::mt19937 rng(23);
  const Sim3 a = test::RandomSim3(rng), b = test::RandomSim3(rng);
  EXPECT_TRUE(MatricesNear(Sim3::Interpolate(a, b, 0).Matrix(), a.Matrix(), 1e-12));
  EXPECT_TRUE(MatricesNear(Sim3::Interpolate(a, b, 1).Matrix(), b.Matrix(), 1e-9));
  EXPECT_NEAR(Sim3::Interpolate(a, b, 0.5).scale(), std::sqrt(a.scale() * b.scale()), 1e-9);
}

TEST(Sim3DeathTest, NonPositiveScaleIsABrokenInvariant) {
  EXPECT_DEATH(Sim3(Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(), 0.0), "scale");
}

}  // namespace
}  // namespace moslam::geometry
