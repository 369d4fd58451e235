#include "moslam/eval/ate.h"

#include <cmath>

#include <gtest/gtest.h>

#include "moslam/eval/test_trajectories.h"
#include "moslam/util/error.h"

namespace moslam::eval {
namespace {

AteOptions Options(Convention convention, AlignmentMode mode) {
  AteOptions o = AteOptions::Defaults(convention);
  o.alignment = mode;
  return o;
}

class AteBothConventions : public ::testing::TestWithParam<Convention> {};

TEST_P(AteBothConventions, IdenticalTrajectoriesHaveZeroError) {
  const Trajectory gt = testing::MakeCurve(100);
  for (const AlignmentMode mode :
       {AlignmentMode::kNone, AlignmentMode::kSe3, AlignmentMode::kSim3, AlignmentMode::kOrigin}) {
    const AteResult r = ComputeAte(gt, gt, Options(GetParam(), mode));
    EXPECT_EQ(r.translation.stats.count, 100u);
    EXPECT_LT(r.translation.stats.max, 1e-9) << AlignmentModeName(mode);
    EXPECT_LT(r.rotation.stats.max, 1e-5) << AlignmentModeName(mode);  // arccos resolution
  }
}

TEST_P(AteBothConventions, ConstantOffsetIsTheErrorWithoutAlignmentAndVanishesWithSe3) {
  const Trajectory gt = testing::MakeCurve(100);
  const Trajectory est = testing::Transformed(
      gt, geometry::Sim3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 2, 2), 1.0));
  const AteResult none = ComputeAte(gt, est, Options(GetParam(), AlignmentMode::kNone));
  EXPECT_NEAR(none.translation.stats.rmse, 3.0, 1e-12);
  EXPECT_NEAR(none.translation.stats.min, 3.0, 1e-12);
  EXPECT_NEAR(none.translation.stats.std, 0.0, 1e-9);
  const AteResult se3 = ComputeAte(gt, est, Options(GetParam(), AlignmentMode::kSe3));
  EXPECT_LT(se3.translation.stats.max, 1e-9);
  EXPECT_NEAR(se3.alignment.translation().norm(), 3.0, 1e-9);
}

TEST_P(AteBothConventions, Sim3RecoversAScaledCopy) {
  const Trajectory gt = testing::MakeCurve(100);
  const Trajectory est = testing::Transformed(gt, testing::SomeSim3(2.5));
  const AteResult sim3 = ComputeAte(gt, est, Options(GetParam(), AlignmentMode::kSim3));
  EXPECT_LT(sim3.translation.stats.max, 1e-9);
  EXPECT_NEAR(sim3.alignment.scale(), 1 / 2.5, 1e-12);
  EXPECT_LT(sim3.rotation.stats.max, 1e-5);
  const AteResult se3 = ComputeAte(gt, est, Options(GetParam(), AlignmentMode::kSe3));
  EXPECT_GT(se3.translation.stats.rmse, 0.1);  // a rigid fit cannot undo the scale
}

TEST_P(AteBothConventions, OriginAlignmentMakesTheFirstPosesCoincide) {
  const Trajectory gt = testing::MakeCurve(50);
  Trajectory est = testing::Transformed(gt, testing::SomeSim3(1.0));
  est.poses[10] = geometry::SE3(est.poses[10].rotation(),
                                est.poses[10].translation() + Eigen::Vector3d(0, 0, 0.5));
  const AteResult r = ComputeAte(gt, est, Options(GetParam(), AlignmentMode::kOrigin));
  EXPECT_NEAR(r.translation.values[0], 0.0, 1e-12);
  EXPECT_NEAR(r.translation.values[10], 0.5, 1e-9);
  EXPECT_NEAR(r.translation.stats.max, 0.5, 1e-9);
}

TEST_P(AteBothConventions, RotationErrorInDegrees) {
  const Trajectory gt = testing::MakeCurve(30);
  Trajectory est = gt;
  const geometry::SE3 turn(geometry::ExpSO3(Eigen::Vector3d(0, 0, 2.0 * M_PI / 180)),
                           Eigen::Vector3d::Zero());
  for (geometry::SE3& pose : est.poses) pose = pose * turn;  // orientation only
  const AteResult r = ComputeAte(gt, est, Options(GetParam(), AlignmentMode::kNone));
  EXPECT_NEAR(r.rotation.stats.mean, 2.0, 1e-6);
  EXPECT_LT(r.translation.stats.max, 1e-12);
}

TEST_P(AteBothConventions, StampsAreAssociatedWithinMaxDt) {
  const Trajectory gt = testing::MakeCurve(100, 0.1);
  Trajectory est = testing::MakeCurve(100, 0.1, 100.004);  // 4 ms late, same poses
  const AteResult r = ComputeAte(gt, est, Options(GetParam(), AlignmentMode::kNone));
  EXPECT_EQ(r.translation.stats.count, 100u);
  EXPECT_LT(r.translation.stats.max, 1e-12);
  AteOptions tight = Options(GetParam(), AlignmentMode::kNone);
  tight.max_dt = 0.001;
  EXPECT_THROW(ComputeAte(gt, est, tight), InputError);  // nothing within 1 ms
  tight.offset = -0.004;
  EXPECT_EQ(ComputeAte(gt, est, tight).translation.stats.count, 100u);
}

INSTANTIATE_TEST_SUITE_P(Conventions, AteBothConventions,
                         ::testing::Values(Convention::kTum, Convention::kEvo));

TEST(Ate, TooFewPairsForAlignmentIsAnInputError) {
  const Trajectory gt = testing::MakeCurve(2);
  EXPECT_THROW(ComputeAte(gt, gt, AteOptions::Defaults(Convention::kTum)), InputError);
}

TEST(Ate, StampedAgainstUnstampedIsAnInputError) {
  const Trajectory gt = testing::MakeCurve(10);
  Trajectory est = gt;
  est.timestamps.clear();
  EXPECT_THROW(ComputeAte(gt, est, AteOptions::Defaults(Convention::kTum)), InputError);
}

TEST(Ate, InvalidOptionsAreInputErrors) {
  AteOptions o;
  o.max_dt = 0;
  EXPECT_THROW(o.Check(), InputError);
  o.max_dt = 0.02;
  o.offset = NAN;
  EXPECT_THROW(o.Check(), InputError);
}

}  // namespace
}  // namespace moslam::eval
