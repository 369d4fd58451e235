// End to end through RunEvaluation, the function behind `moslam eval ate|rpe`.
#include "moslam/eval/evaluate.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/eval/test_trajectories.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::eval {
namespace {

using moslam::testing::TempDir;
using ::testing::HasSubstr;

class Evaluate : public ::testing::Test {
 protected:
  void SetUp() override {
    const Trajectory gt = testing::MakeCurve(100);
    request_.inputs.gt_path = dir_.path() + "/gt.txt";
    request_.inputs.est_path = dir_.path() + "/est.txt";
    WriteTum(gt, request_.inputs.gt_path);
    WriteTum(testing::Transformed(gt, geometry::Sim3(Eigen::Quaterniond::Identity(),
                                                     Eigen::Vector3d(0, 0.3, 0.4), 1.0)),
             request_.inputs.est_path);
  }
  TempDir dir_;
  EvalRequest request_;
};

TEST_F(Evaluate, AteTextTable) {
  request_.alignment = "none";
  const EvalOutput out = RunEvaluation(request_);
  EXPECT_THAT(out.text, HasSubstr("ATE, convention tum: association greedy (associate.py) within "
                                  "0.02 s, offset 0 s; alignment none"));
  EXPECT_THAT(out.text, HasSubstr("  compared_pose_pairs  100\n"));
  EXPECT_THAT(out.text, HasSubstr("  rmse                     0.500000 m\n"));
  EXPECT_FALSE(out.plot.has_value());
}

TEST_F(Evaluate, DefaultsFollowTheConvention) {
  TrajectoryPair pair = LoadTrajectories(request_.inputs);
  EXPECT_EQ(MakeAteOptions(request_, pair).alignment, AlignmentMode::kSe3);
  EXPECT_EQ(MakeAteOptions(request_, pair).max_dt, 0.02);
  request_.convention = "evo";
  EXPECT_EQ(MakeAteOptions(request_, pair).max_dt, 0.01);
  EXPECT_EQ(MakeRpeOptions(request_, pair).delta_unit, DeltaUnit::kFrames);
  EXPECT_EQ(MakeRpeOptions(request_, pair).alignment, AlignmentMode::kNone);
  request_.convention = "auto";
  EXPECT_EQ(MakeRpeOptions(request_, pair).delta_unit, DeltaUnit::kSeconds);
  pair.gt.timestamps.clear();
  pair.est.timestamps.clear();
  EXPECT_EQ(MakeRpeOptions(request_, pair).convention, Convention::kEvo);  // KITTI-like
}

TEST_F(Evaluate, RpeJson) {
  request_.metric = Metric::kRpe;
  request_.json = true;
  const nlohmann::json j = nlohmann::json::parse(RunEvaluation(request_).text);
  EXPECT_EQ(j["metric"], "rpe");
  EXPECT_EQ(j["delta_unit"], "s");
  EXPECT_EQ(j["compared_pose_pairs"], 89);
  EXPECT_LT(j["translation_m"]["rmse"].get<double>(), 1e-12);
  EXPECT_EQ(j["ground_truth"]["poses"], 100);
}

TEST_F(Evaluate, PlotDataIsFilled) {
  request_.plot_path = dir_.path() + "/ate.svg";
  request_.rotation = true;
  const EvalOutput out = RunEvaluation(request_);
  ASSERT_TRUE(out.plot.has_value());
  EXPECT_EQ(out.plot->times.size(), 100u);
  EXPECT_EQ(out.plot->times.front(), 0.0);
  EXPECT_EQ(out.plot->reference.size(), 100u);
  EXPECT_EQ(out.plot->estimate.size(), 100u);
  EXPECT_EQ(out.plot->errors.size(), 100u);
  EXPECT_EQ(out.plot->error_label, "ATE rot. [deg]");
  EXPECT_EQ(out.plot->title, "ATE, SE(3)-aligned: est.txt");
  // Aligned: the estimate lies on the reference.
  EXPECT_LT((out.plot->estimate[5] - out.plot->reference[5]).norm(), 1e-9);
  EXPECT_EQ(out.plot->time_label, "time since start [s]");  // TUM files carry seconds
}

TEST_F(Evaluate, PlotOfFilesWithoutTimestampsIsOverFrames) {
  // KITTI poses carry no timestamps: the plot's time axes count frames, not seconds.
  const Trajectory gt = testing::MakeCurve(50);
  request_.inputs.gt_path = dir_.path() + "/gt_kitti.txt";
  request_.inputs.est_path = dir_.path() + "/est_kitti.txt";
  WriteKitti(gt, request_.inputs.gt_path);
  WriteKitti(gt, request_.inputs.est_path);
  request_.plot_path = dir_.path() + "/ate.png";
  const EvalOutput ate = RunEvaluation(request_);
  ASSERT_TRUE(ate.plot.has_value());
  EXPECT_EQ(ate.plot->time_label, "frame");
  EXPECT_EQ(ate.plot->times.back(), 49.0);
  request_.metric = Metric::kRpe;
  const EvalOutput rpe = RunEvaluation(request_);
  ASSERT_TRUE(rpe.plot.has_value());
  EXPECT_EQ(rpe.plot->time_label, "frame");
}

// Issue 31: files matched by index with different lengths said so without naming either file.
TEST_F(Evaluate, IndexMatchedFilesOfDifferentLengthsAreNamed) {
  const Trajectory gt = testing::MakeCurve(300);
  request_.inputs.gt_path = dir_.path() + "/gt_kitti.txt";
  request_.inputs.est_path = dir_.path() + "/est_kitti.txt";
  WriteKitti(gt, request_.inputs.gt_path);
  for (const Metric metric : {Metric::kAte, Metric::kRpe}) {
    for (const int rows : {1, 2, 150}) {
      Trajectory est = gt;
      est.poses.resize(rows);
      est.raw_rotations.clear();
      if (!est.timestamps.empty()) est.timestamps.resize(rows);
      WriteKitti(est, request_.inputs.est_path);
      request_.metric = metric;
      EXPECT_THAT(
          moslam::testing::ErrorOf([&] { RunEvaluation(request_); }),
          ::testing::AllOf(HasSubstr(request_.inputs.gt_path), HasSubstr(request_.inputs.est_path),
                           HasSubstr("300"), HasSubstr(std::to_string(rows))))
          << rows << " rows";
    }
  }
}

TEST_F(Evaluate, BadSettingsAreInputErrors) {
  request_.convention = "orb";
  EXPECT_THROW(RunEvaluation(request_), InputError);
  request_.convention = "evo";
  request_.metric = Metric::kRpe;
  request_.delta_unit = "s";
  EXPECT_THROW(RunEvaluation(request_), InputError);
}

TEST(EvaluateShared, Fr2DeskAteAsTheCliPrintsIt) {
  MOSLAM_SHARED_OR_SKIP(dir, "data/trajectories");
  EvalRequest request;
  request.inputs.gt_path = dir + "/fr2_desk_groundtruth.txt";
  request.inputs.est_path = dir + "/fr2_desk_ORB.txt";
  const std::string text = RunEvaluation(request).text;
  EXPECT_THAT(text, HasSubstr("compared_pose_pairs  2223"));
  EXPECT_THAT(text, HasSubstr("rmse                     0.008144 m"));
}

TEST(EvaluateShared, KittiGroundTruthWithTimesAgainstTumEstimate) {
  MOSLAM_SHARED_OR_SKIP(dir, "data/trajectories");
  TempDir scratch;
  Trajectory est = ReadTrajectory(dir + "/KITTI_00_ORB.txt");
  est.timestamps = ReadTimes(dir + "/KITTI_00_gt_times.txt");
  const std::string est_path = scratch.path() + "/est_tum.txt";
  WriteTum(est, est_path);
  EvalRequest request;
  request.inputs.gt_path = dir + "/KITTI_00_gt.txt";
  request.inputs.est_path = est_path;
  request.convention = "evo";
  EXPECT_THROW(RunEvaluation(request), InputError);  // gt has no stamps
  request.inputs.gt_times = dir + "/KITTI_00_gt_times.txt";
  EXPECT_THAT(RunEvaluation(request).text, HasSubstr("rmse                     1.303450 m"));
}

}  // namespace
}  // namespace moslam::eval
