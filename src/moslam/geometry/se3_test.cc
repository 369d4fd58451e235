#include "moslam/geometry/se3.h"

#include <random>

#include <gtest/gtest.h>

#include "moslam/geometry/test_util.h"

namespace moslam::geometry {
namespace {

using test::MatricesNear;

TEST(SE3, GroupAxioms) {
  std::mt19937 rng(10);
  for (int i = 0; i < 30; ++i) {
    const SE3 a = test::RandomSE3(rng), b = test::RandomSE3(rng), c = test::RandomSE3(rng);
    // Associativity, identity, inverse.
    EXPECT_TRUE(MatricesNear(((a * b) * c).Matrix(), (a * (b * c)).Matrix(), 1e-12));
    EXPECT_TRUE(MatricesNear((a * SE3::Identity()).Matrix(), a.Matrix(), 1e-15));
    EXPECT_TRUE(MatricesNear((SE3::Identity() * a).Matrix(), a.Matrix(), 1e-15));
    EXPECT_TRUE(MatricesNear((a * a.Inverse()).Matrix(), Eigen::Matrix4d::Identity(), 1e-12));
    EXPECT_TRUE(MatricesNear((a.Inverse() * a).Matrix(), Eigen::Matrix4d::Identity(), 1e-12));
    // The group product is the matrix product.
    EXPECT_TRUE(MatricesNear((a * b).Matrix(), a.Matrix() * b.Matrix(), 1e-12));
  }
}

TEST(SE3, FrameConventionMapsPointsFromSecondToFirstFrame) {
  // Camera 2 m along world x, looking along world x (its z axis), y down: T_world_cam.
  Eigen::Matrix3d R_world_cam;
  R_world_cam << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const SE3 T_world_cam(R_world_cam, Eigen::Vector3d(2, 0, 0));
  const Eigen::Vector3d p_cam(0, 0, 3);  // 3 m in front of the camera
  EXPECT_TRUE(MatricesNear(T_world_cam * p_cam, Eigen::Vector3d(5, 0, 0), 1e-15));
  EXPECT_TRUE(MatricesNear(T_world_cam.Inverse() * Eigen::Vector3d(5, 0, 0), p_cam, 1e-15));
  // Chaining: T_a_c = T_a_b * T_b_c.
  std::mt19937 rng(11);
  const SE3 T_a_b = test::RandomSE3(rng), T_b_c = test::RandomSE3(rng);
  const Eigen::Vector3d p_c = test::RandomVector(rng, 3);
  EXPECT_TRUE(MatricesNear((T_a_b * T_b_c) * p_c, T_a_b * (T_b_c * p_c), 1e-12));
}

TEST(SE3, ExpLogRoundTrip) {
  std::mt19937 rng(12);
  for (double scale : {0.0, 1e-9, 1e-5, 0.1, 1.0, 2.5}) {
    for (int i = 0; i < 10; ++i) {
      Vector6d xi;
      // Rotation angle = scale < pi, where Log is the inverse of Exp.
      xi << test::RandomVector(rng, 3), test::RandomVector(rng, 1).normalized() * scale;
      EXPECT_TRUE(MatricesNear(SE3::Exp(xi).Log(), xi, 1e-10)) << "scale " << scale;
      const SE3 T = test::RandomSE3(rng);
      EXPECT_TRUE(MatricesNear(SE3::Exp(T.Log()).Matrix(), T.Matrix(), 1e-10));
    }
  }
}

TEST(SE3, ExpOfPureTranslationAndPureRotation) {
  Vector6d xi = Vector6d::Zero();
  xi.head<3>() << 1, 2, 3;
  EXPECT_TRUE(MatricesNear(SE3::Exp(xi).translation(), Eigen::Vector3d(1, 2, 3), 0));
  xi.setZero();
  xi(5) = M_PI / 2;  // 90 degrees about z
  EXPECT_TRUE(
      MatricesNear(SE3::Exp(xi) * Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0), 1e-15));
}

TEST(SE3, InterpolationEndpointsAndMidpoint) {
  std::mt19937 rng(13);
  const SE3 a = test::RandomSE3(rng), b = test::RandomSE3(rng);
  EXPECT_TRUE(MatricesNear(SE3::Interpolate(a, b, 0).Matrix(), a.Matrix(), 1e-12));
  EXPECT_TRUE(MatricesNear(SE3::Interpolate(a, b, 1).Matrix(), b.Matrix(), 1e-10));
  // The midpoint m satisfies a^-1 m = m^-1 b (equal steps along the geodesic).
  const SE3 m = SE3::Interpolate(a, b, 0.5);
  EXPECT_TRUE(MatricesNear((a.Inverse() * m).Matrix(), (m.Inverse() * b).Matrix(), 1e-10));
  // Between two poses that differ by a pure translation, interpolation is linear.
  const SE3 c(a.rotation(), a.translation() + Eigen::Vector3d(1, 0, 0));
  EXPECT_TRUE(MatricesNear(SE3::Interpolate(a, c, 0.25).translation(),
                           a.translation() + Eigen::Vector3d(0.25, 0, 0), 1e-12));
}

TEST(SE3, FromMatrix3x4RoundTrip) {
  std::mt19937 rng(14);
  const SE3 T = test::RandomSE3(rng);
  EXPECT_TRUE(MatricesNear(SE3::FromMatrix3x4(T.Matrix3x4()).Matrix(), T.Matrix(), 1e-12));
}

TEST(SE3DeathTest, ZeroQuaternionIsABrokenInvariant) {
  EXPECT_DEATH(SE3(Eigen::Quaterniond(0, 0, 0, 0), Eigen::Vector3d::Zero()), "zero");
  Eigen::Matrix3d shear = Eigen::Matrix3d::Identity();
  shear(0, 1) = 0.5;
  EXPECT_DEATH(SE3(shear, Eigen::Vector3d::Zero()), "not a rotation");
}

}  // namespace
}  // namespace moslam::geometry
