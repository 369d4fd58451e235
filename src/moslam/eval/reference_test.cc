// Agreement with the reference tools: every number of shared/data/trajectories/REFERENCE.md, at
// its printed precision (half a unit of the last printed digit), pair counts exactly.
#include <gtest/gtest.h>

#include "moslam/eval/ate.h"
#include "moslam/eval/rpe.h"
#include "moslam/eval/trajectory_io.h"
#include "moslam/testing/shared_data.h"

namespace moslam::eval {
namespace {

constexpr double kPrinted = 5e-7;  // half a unit of the 6th decimal

struct Expected {
  double rmse, mean, median, std;
};

void ExpectStats(const ErrorStatistics& s, const Expected& e) {
  EXPECT_NEAR(s.rmse, e.rmse, kPrinted);
  EXPECT_NEAR(s.mean, e.mean, kPrinted);
  EXPECT_NEAR(s.median, e.median, kPrinted);
  EXPECT_NEAR(s.std, e.std, kPrinted);
}

class Fr2Desk : public ::testing::Test {
 protected:
  void SetUp() override {
    MOSLAM_SHARED_OR_SKIP(dir, "data/trajectories");
    gt_ = ReadTrajectory(dir + "/fr2_desk_groundtruth.txt");
    est_ = ReadTrajectory(dir + "/fr2_desk_ORB.txt");
  }
  Trajectory gt_, est_;
};

TEST_F(Fr2Desk, TumEvaluateAte) {
  const AteResult r = ComputeAte(gt_, est_, AteOptions::Defaults(Convention::kTum));
  const ErrorStatistics& s = r.translation.stats;
  EXPECT_EQ(s.count, 2223u);
  ExpectStats(s, {0.008144, 0.007514, 0.007432, 0.003140});
  EXPECT_NEAR(s.min, 0.000332, kPrinted);
  EXPECT_NEAR(s.max, 0.024329, kPrinted);
}

TEST_F(Fr2Desk, TumEvaluateRpeOneSecond) {
  RpeOptions o = RpeOptions::Defaults(Convention::kTum);  // --fixed_delta --delta 1 --delta_unit s
  const RpeResult r = ComputeRpe(gt_, est_, o);
  const ErrorStatistics& t = r.translation.stats;
  EXPECT_EQ(t.count, 1998u);
  ExpectStats(t, {0.007161, 0.006502, 0.006218, 0.003001});
  EXPECT_NEAR(t.min, 0.000167, kPrinted);
  EXPECT_NEAR(t.max, 0.021224, kPrinted);
  const ErrorStatistics& a = r.rotation.stats;
  ExpectStats(a, {0.455005, 0.401638, 0.365846, 0.213814});
  EXPECT_NEAR(a.min, 0.008244, kPrinted);
  EXPECT_NEAR(a.max, 1.732641, kPrinted);
}

TEST_F(Fr2Desk, TumEvaluateRpeOneFrame) {
  RpeOptions o = RpeOptions::Defaults(Convention::kTum);
  o.delta_unit = DeltaUnit::kFrames;
  const RpeResult r = ComputeRpe(gt_, est_, o);
  EXPECT_EQ(r.translation.stats.count, 2060u);
  ExpectStats(r.translation.stats, {0.003381, 0.002972, 0.002700, 0.001613});
  ExpectStats(r.rotation.stats, {0.266378, 0.219859, 0.180846, 0.150397});
}

TEST_F(Fr2Desk, EvoApeSe3) {
  const AteResult r = ComputeAte(gt_, est_, AteOptions::Defaults(Convention::kEvo));  // -a
  const ErrorStatistics& s = r.translation.stats;
  ExpectStats(s, {0.008119, 0.007492, 0.007415, 0.003129});
  EXPECT_NEAR(s.min, 0.000350, kPrinted);
  EXPECT_NEAR(s.max, 0.024300, kPrinted);
}

RpeOptions EvoRpe(DeltaUnit unit) {
  RpeOptions o = RpeOptions::Defaults(Convention::kEvo);
  o.alignment = AlignmentMode::kSe3;  // -a
  o.delta_unit = unit;
  return o;
}

TEST_F(Fr2Desk, EvoRpeOneFrame) {
  const RpeResult r = ComputeRpe(gt_, est_, EvoRpe(DeltaUnit::kFrames));
  ExpectStats(r.translation.stats, {0.003490, 0.003038, 0.002750, 0.001718});
  EXPECT_NEAR(r.translation.stats.max, 0.019485, kPrinted);
  EXPECT_NEAR(r.rotation.stats.rmse, 0.280519, kPrinted);  // -r angle_deg
  EXPECT_NEAR(r.rotation.stats.mean, 0.229556, kPrinted);
  EXPECT_NEAR(r.rotation.stats.median, 0.187818, kPrinted);
}

TEST_F(Fr2Desk, EvoRpeOneMetrePairsOnTheEstimate) {
  const RpeResult r = ComputeRpe(gt_, est_, EvoRpe(DeltaUnit::kMetres));
  EXPECT_NEAR(r.translation.stats.rmse, 0.011653, kPrinted);
  EXPECT_NEAR(r.translation.stats.mean, 0.010557, kPrinted);
  EXPECT_NEAR(r.translation.stats.median, 0.009853, kPrinted);
}

class Kitti00 : public ::testing::Test {
 protected:
  void SetUp() override {
    MOSLAM_SHARED_OR_SKIP(dir, "data/trajectories");
    gt_ = ReadTrajectory(dir + "/KITTI_00_gt.txt");
    est_ = ReadTrajectory(dir + "/KITTI_00_ORB.txt");
  }
  AteResult Ape(AlignmentMode mode) const {
    AteOptions o = AteOptions::Defaults(Convention::kEvo);
    o.alignment = mode;
    return ComputeAte(gt_, est_, o);
  }
  Trajectory gt_, est_;
};

TEST_F(Kitti00, EvoApe) {
  ExpectStats(Ape(AlignmentMode::kNone).translation.stats,
              {7.790289, 7.011750, 6.801632, 3.394695});
  const AteResult se3 = Ape(AlignmentMode::kSe3);
  ExpectStats(se3.translation.stats, {1.303450, 1.156997, 1.065625, 0.600282});
  EXPECT_NEAR(se3.translation.stats.max, 3.587949, kPrinted);
  ExpectStats(Ape(AlignmentMode::kSim3).translation.stats,
              {0.937709, 0.872693, 0.844691, 0.343083});
}

TEST_F(Kitti00, EvoRpe) {
  RpeOptions o = RpeOptions::Defaults(Convention::kEvo);
  ExpectStats(ComputeRpe(gt_, est_, o).translation.stats, {0.028120, 0.019301, 0.014709, 0.020450});
  o.delta = 100;
  o.delta_unit = DeltaUnit::kMetres;
  // Reproduced only with the rotations as read (Trajectory::raw_rotations): re-orthonormalized
  // ones give a median of 0.895178.
  ExpectStats(ComputeRpe(gt_, est_, o).translation.stats, {1.102742, 1.000045, 0.895180, 0.464704});
}

TEST_F(Kitti00, TumConventionByIndexEqualsEvoForSe3Ape) {
  // Horn and Umeyama reach the same optimum; with index association the conventions agree.
  AteOptions o = AteOptions::Defaults(Convention::kTum);
  EXPECT_NEAR(ComputeAte(gt_, est_, o).translation.stats.rmse, 1.303450, kPrinted);
}

TEST(KittiWithTimes, TumFormatEstimateMatchedByTimeEqualsIndexMatch) {
  MOSLAM_SHARED_OR_SKIP(dir, "data/trajectories");
  const Trajectory est_kitti = ReadTrajectory(dir + "/KITTI_00_ORB.txt");
  Trajectory gt = ReadTrajectory(dir + "/KITTI_00_gt.txt");
  AttachTimes(dir + "/KITTI_00_gt_times.txt", &gt);
  // A keyframe-like TUM estimate: every third pose, stamped from times.txt.
  std::vector<size_t> keyframes;
  for (size_t i = 0; i < est_kitti.size(); i += 3) keyframes.push_back(i);
  Trajectory est = est_kitti.Subset(keyframes);
  for (const size_t i : keyframes) est.timestamps.push_back(gt.timestamps[i]);
  est.raw_rotations.clear();
  AteOptions o = AteOptions::Defaults(Convention::kEvo);
  const AteResult by_time = ComputeAte(gt, est, o);
  EXPECT_EQ(by_time.translation.stats.count, keyframes.size());
  const Trajectory gt_index = ReadTrajectory(dir + "/KITTI_00_gt.txt").Subset(keyframes);
  const AteResult by_index = ComputeAte(gt_index, est_kitti.Subset(keyframes), o);
  EXPECT_NEAR(by_time.translation.stats.rmse, by_index.translation.stats.rmse, 1e-9);
}

}  // namespace
}  // namespace moslam::eval
