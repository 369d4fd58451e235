#include "moslam/eval/rpe.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/eval/test_trajectories.h"
#include "moslam/util/error.h"

namespace moslam::eval {
namespace {

using ::testing::ElementsAre;
using ::testing::Pair;

// An estimate that follows every ground-truth step and then moves by `drift`:
// P_{i+1} = P_i * (Q_i^-1 Q_{i+1}) * drift.
Trajectory WithDrift(const Trajectory& gt, const geometry::SE3& drift) {
  Trajectory est = gt;
  for (size_t i = 0; i + 1 < gt.size(); ++i) {
    est.poses[i + 1] = est.poses[i] * (gt.poses[i].Inverse() * gt.poses[i + 1]) * drift;
  }
  return est;
}

RpeOptions Frames(Convention convention) {
  RpeOptions o = RpeOptions::Defaults(convention);
  o.delta_unit = DeltaUnit::kFrames;
  return o;
}

TEST(Rpe, IdenticalTrajectoriesHaveZeroError) {
  const Trajectory gt = testing::MakeCurve(60);
  for (const Convention c : {Convention::kTum, Convention::kEvo}) {
    const RpeResult r = ComputeRpe(gt, gt, Frames(c));
    EXPECT_LT(r.translation.stats.max, 1e-12);
    EXPECT_LT(r.rotation.stats.max, 1e-5);
  }
}

TEST(Rpe, EvoPerStepDriftIsTheErrorOfEveryConsecutivePair) {
  const Trajectory gt = testing::MakeCurve(60);
  const geometry::SE3 drift(geometry::ExpSO3(Eigen::Vector3d(0, 0.5 * M_PI / 180, 0)),
                            Eigen::Vector3d(0.03, 0.0, 0.04));
  const RpeResult r = ComputeRpe(gt, WithDrift(gt, drift), Frames(Convention::kEvo));
  EXPECT_EQ(r.translation.stats.count, 59u);  // ids 0..59, consecutive
  EXPECT_NEAR(r.translation.stats.min, 0.05, 1e-12);
  EXPECT_NEAR(r.translation.stats.max, 0.05, 1e-12);
  EXPECT_NEAR(r.rotation.stats.mean, 0.5, 1e-6);
  EXPECT_THAT(r.pairs.front(), Pair(0u, 1u));
}

TEST(Rpe, TumPerStepTranslationDriftDropsThePairEndingAtTheLastPose) {
  const Trajectory gt = testing::MakeCurve(60);
  const geometry::SE3 drift(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 0.05, 0.0));
  const RpeResult r = ComputeRpe(gt, WithDrift(gt, drift), Frames(Convention::kTum));
  EXPECT_EQ(r.translation.stats.count, 58u);  // (58, 59) is dropped as evaluate_rpe.py does
  EXPECT_NEAR(r.translation.stats.min, 0.05, 1e-12);
  EXPECT_NEAR(r.translation.stats.max, 0.05, 1e-12);
  EXPECT_LT(r.rotation.stats.max, 1e-5);
}

TEST(Rpe, TumDeltaInSecondsPairsPosesOneSecondApart) {
  const Trajectory gt = testing::MakeCurve(100, 0.1);
  const RpeResult r = ComputeRpe(gt, gt, RpeOptions::Defaults(Convention::kTum));
  EXPECT_EQ(r.translation.stats.count, 89u);  // i + 10 <= 98
  EXPECT_THAT(r.pairs.front(), Pair(0u, 10u));
}

TEST(Rpe, RigidAlignmentDoesNotChangeRpeButSim3Rescales) {
  const Trajectory gt = testing::MakeCurve(80);
  const geometry::SE3 drift(geometry::ExpSO3(Eigen::Vector3d(0.01, 0, 0)),
                            Eigen::Vector3d(0.02, 0.0, 0.0));
  const Trajectory est = WithDrift(gt, drift);
  for (const Convention c : {Convention::kTum, Convention::kEvo}) {
    RpeOptions o = Frames(c);
    const double plain = ComputeRpe(gt, est, o).translation.stats.rmse;
    const Trajectory moved = testing::Transformed(est, testing::SomeSim3(1.0));
    EXPECT_NEAR(ComputeRpe(gt, moved, o).translation.stats.rmse, plain, 1e-12);
    const Trajectory scaled = testing::Transformed(gt, testing::SomeSim3(3.0));
    EXPECT_GT(ComputeRpe(gt, scaled, o).translation.stats.rmse, 0.01);
    o.alignment = AlignmentMode::kSim3;
    EXPECT_LT(ComputeRpe(gt, scaled, o).translation.stats.max, 1e-9);
  }
}

// A straight line along x with 0.1 m steps.
Trajectory Line(size_t n) {
  Trajectory t;
  t.name = "line";
  for (size_t i = 0; i < n; ++i) {
    t.timestamps.push_back(static_cast<double>(i));
    t.poses.emplace_back(Eigen::Quaterniond::Identity(),
                         Eigen::Vector3d(0.1 * static_cast<double>(i), 0, 0));
  }
  return t;
}

TEST(Rpe, EvoMetresSetAnIdWheneverThePathReachesDelta) {
  const Trajectory t = Line(36);
  RpeOptions o = RpeOptions::Defaults(Convention::kEvo);
  o.delta = 0.95;
  o.delta_unit = DeltaUnit::kMetres;
  const RpeResult r = ComputeRpe(t, t, o);
  // The path reaches 0.95 m at pose 10 (1.0 m), then again 10 poses later each time.
  EXPECT_THAT(r.pairs, ElementsAre(Pair(10u, 20u), Pair(20u, 30u)));
  o.all_pairs = true;
  o.delta = 1.02;  // tolerance 0.102 m: j = i + 10, for every i with i + 10 <= 35
  EXPECT_EQ(ComputeRpe(t, t, o).pairs.size(), 26u);
}

TEST(Rpe, EvoFramesAllPairs) {
  const Trajectory t = Line(20);
  RpeOptions o = Frames(Convention::kEvo);
  o.delta = 3;
  EXPECT_EQ(ComputeRpe(t, t, o).pairs.size(), 6u);  // 0-3, 3-6, ..., 15-18
  o.all_pairs = true;
  EXPECT_EQ(ComputeRpe(t, t, o).pairs.size(), 17u);
}

TEST(Rpe, EvoDegreesAccumulateRotation) {
  Trajectory t = Line(40);
  for (size_t i = 0; i < t.size(); ++i) {  // 1 degree per pose about z
    t.poses[i] =
        geometry::SE3(geometry::ExpSO3(Eigen::Vector3d(0, 0, static_cast<double>(i) * M_PI / 180)),
                      t.Position(i));
  }
  RpeOptions o = RpeOptions::Defaults(Convention::kEvo);
  o.delta = 9.5;
  o.delta_unit = DeltaUnit::kDegrees;
  EXPECT_THAT(ComputeRpe(t, t, o).pairs,
              ElementsAre(Pair(0u, 10u), Pair(10u, 20u), Pair(20u, 30u)));
}

TEST(Rpe, TumAllPairsAreEveryOrderedPairOrASeededSample) {
  const Trajectory t = Line(30);
  RpeOptions o = RpeOptions::Defaults(Convention::kTum);
  o.all_pairs = true;
  EXPECT_EQ(ComputeRpe(t, t, o).pairs.size(), 900u);  // 30 < sqrt(10000)
  o.max_pairs = 100;                                  // 30 >= sqrt(100): sample
  const RpeResult a = ComputeRpe(t, t, o);
  EXPECT_EQ(a.pairs.size(), 100u);
  EXPECT_EQ(ComputeRpe(t, t, o).pairs, a.pairs);  // deterministic for a seed
}

TEST(Rpe, FindClosestIndexFollowsTheScript) {
  const std::vector<double> v = {0.0, 1.0, 2.0, 3.0, 4.0};
  EXPECT_EQ(FindClosestIndex(v, 2.2), 2u);
  EXPECT_EQ(FindClosestIndex(v, 2.0), 2u);
  EXPECT_EQ(FindClosestIndex(v, -5.0), 0u);
  EXPECT_EQ(FindClosestIndex(v, 10.0), 4u);
}

TEST(Rpe, InvalidSettingsAreInputErrors) {
  const Trajectory t = Line(20);
  RpeOptions o = RpeOptions::Defaults(Convention::kEvo);
  o.delta_unit = DeltaUnit::kSeconds;
  EXPECT_THROW(ComputeRpe(t, t, o), InputError);  // evo has no seconds
  o = Frames(Convention::kEvo);
  o.delta = 1.5;
  EXPECT_THROW(ComputeRpe(t, t, o), InputError);
  o.delta = 100;
  EXPECT_THROW(ComputeRpe(t, t, o), InputError);  // no pair
  EXPECT_THROW(ParseDeltaUnit("km"), InputError);
  EXPECT_EQ(ParseDeltaUnit("deg"), DeltaUnit::kDegrees);
}

}  // namespace
}  // namespace moslam::eval
