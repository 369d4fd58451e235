#include "moslam/geometry/alignment.h"

#include <random>

#include <gtest/gtest.h>

#include "moslam/geometry/test_util.h"

namespace moslam::geometry {
namespace {

using test::MatricesNear;

Eigen::Matrix3Xd RandomCloud(std::mt19937& rng, int n) {
  Eigen::Matrix3Xd points(3, n);
  for (int i = 0; i < n; ++i) points.col(i) = test::RandomVector(rng, 4);
  return points;
}

Eigen::Matrix3Xd Transform(const Sim3& S, const Eigen::Matrix3Xd& points) {
  Eigen::Matrix3Xd out(3, points.cols());
  for (int i = 0; i < points.cols(); ++i) out.col(i) = S * Eigen::Vector3d(points.col(i));
  return out;
}

void AddNoise(std::mt19937& rng, double sigma, Eigen::Matrix3Xd* points) {
  std::normal_distribution<double> n(0.0, sigma);
  for (int i = 0; i < points->size(); ++i) points->data()[i] += n(rng);
}

TEST(Alignment, ExactRecoveryWithoutNoise) {
  std::mt19937 rng(30);
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Matrix3Xd source = RandomCloud(rng, 20);
    const SE3 T = test::RandomSE3(rng);
    const Eigen::Matrix3Xd target = Transform(Sim3(T), source);
    const auto horn = AlignHorn(source, target);
    ASSERT_TRUE(horn.has_value());
    EXPECT_TRUE(MatricesNear(horn->Matrix(), T.Matrix(), 1e-10));
    const auto umeyama = AlignUmeyama(source, target, false);
    ASSERT_TRUE(umeyama.has_value());
    EXPECT_TRUE(MatricesNear(umeyama->Matrix(), T.Matrix(), 1e-10));
    EXPECT_EQ(umeyama->scale(), 1.0);
    const Sim3 S = test::RandomSim3(rng);
    const auto scaled = AlignUmeyama(source, Transform(S, source), true);
    ASSERT_TRUE(scaled.has_value());
    EXPECT_TRUE(MatricesNear(scaled->Matrix(), S.Matrix(), 1e-9));
  }
}

TEST(Alignment, RecoversKnownTransformUnderNoise) {
  std::mt19937 rng(31);
  const Eigen::Matrix3Xd source = RandomCloud(rng, 2000);
  const Sim3 S(ExpSO3({0.3, -0.5, 1.2}), Eigen::Vector3d(1, -2, 0.5), 1.7);
  Eigen::Matrix3Xd target = Transform(S, source);
  AddNoise(rng, 0.01, &target);
  const auto sim = AlignUmeyama(source, target, true);
  ASSERT_TRUE(sim.has_value());
  EXPECT_NEAR(sim->scale(), 1.7, 1e-3);
  EXPECT_LT(RotationAngle(sim->rotation() * S.rotation().conjugate()), 1e-3);
  EXPECT_LT((sim->translation() - S.translation()).norm(), 2e-3);

  const SE3 T(ExpSO3({-0.2, 0.1, 0.4}), Eigen::Vector3d(0.3, 0.2, -1));
  Eigen::Matrix3Xd rigid_target = Transform(Sim3(T), source);
  AddNoise(rng, 0.01, &rigid_target);
  const auto horn = AlignHorn(source, rigid_target);
  const auto umeyama = AlignUmeyama(source, rigid_target, false);
  ASSERT_TRUE(horn && umeyama);
  EXPECT_LT(RotationAngle(horn->rotation() * T.rotation().conjugate()), 1e-3);
  EXPECT_LT((horn->translation() - T.translation()).norm(), 2e-3);
  // Both minimize the same cost, so they agree to rounding.
  EXPECT_TRUE(MatricesNear(horn->Matrix(), umeyama->Matrix(), 1e-9));
}

TEST(Alignment, RejectsTooFewOrCollinearPoints) {
  Eigen::Matrix3Xd two(3, 2);
  two << 0, 1, 0, 0, 0, 0;
  EXPECT_FALSE(AlignHorn(two, two).has_value());
  EXPECT_FALSE(AlignUmeyama(two, two, true).has_value());
  Eigen::Matrix3Xd line(3, 5);
  for (int i = 0; i < 5; ++i) line.col(i) = Eigen::Vector3d(i, 2.0 * i, -i);
  EXPECT_FALSE(AlignHorn(line, line).has_value());
  EXPECT_FALSE(AlignUmeyama(line, line, false).has_value());
}

TEST(Alignment, NeverReturnsAReflection) {
  // A mirrored target: the best proper rotation has det +1, never -1.
  std::mt19937 rng(32);
  const Eigen::Matrix3Xd source = RandomCloud(rng, 50);
  Eigen::Matrix3Xd mirrored = source;
  mirrored.row(0) *= -1;
  const auto horn = AlignHorn(source, mirrored);
  const auto umeyama = AlignUmeyama(source, mirrored, true);
  ASSERT_TRUE(horn && umeyama);
  EXPECT_NEAR(horn->rotation_matrix().determinant(), 1.0, 1e-12);
  EXPECT_NEAR(umeyama->rotation_matrix().determinant(), 1.0, 1e-12);
}

}  // namespace
}  // namespace moslam::geometry
