// End-to-end: stereo SLAM on KITTI 06, frames 0-50 (issue 5's acceptance sequence).
#include <memory>

#include <gtest/gtest.h>
#ifdef __linux__
#include <sched.h>
#endif

#include "moslam/slam/run_dataset.h"
#include "moslam/testing/shared_data.h"

namespace moslam::slam {
namespace {

// ORB-SLAM2 reaches 0.042-0.055 m ATE RMSE (SE(3)) on these frames; the bound leaves room for
// run-to-run variation but fails when tracking regresses (a drifting or broken tracker is off by
// metres over the ~40 m of these frames).
constexpr double kMaxAteRmse = 0.10;

TEST(SystemKitti, Kitti06First51FramesTrackedAccurately) {
  MOSLAM_SHARED_OR_SKIP(folder, "data/kitti/06_000000-000050");
  const DatasetRun run = RunDataset(folder, "configs/KITTI04-12.yaml", /*deterministic=*/true);
  ASSERT_EQ(run.reports.size(), 51u);
  for (size_t i = 0; i < run.reports.size(); ++i) {
    EXPECT_EQ(run.reports[i].state, TrackingState::kOk)
        << "frame " << i << ": " << run.reports[i].reason;
  }
  EXPECT_EQ(run.estimate.size(), 51u);
  EXPECT_GT(run.summary.keyframes, 1);
  EXPECT_GE(run.ate_rmse, 0.0);
  EXPECT_LT(run.ate_rmse, kMaxAteRmse);
  // Issue 29: with far disparities weighted by depth (the stereo default) the scale is 0.99937
  // here; with every disparity at full weight (ORB-SLAM2) 0.99764, a trajectory 0.24 % too long.
  // The bound leaves room for another CPU's rounding and fails if the bias comes back.
  EXPECT_NEAR(run.sim3_scale, 1.0, 0.0015);
  std::printf(
      "KITTI 06 0-50: ATE RMSE %.4f m, Sim(3) scale %.5f, %d keyframes, %d points, median %.1f "
      "ms/frame\n",
      run.ate_rmse, run.sim3_scale, run.summary.keyframes, run.summary.map_points,
      run.track_ms_median);
}

TEST(SystemKitti, DeterministicRunsAreIdentical) {
  MOSLAM_SHARED_OR_SKIP(folder, "data/kitti/06_000000-000050");
  const DatasetRun a = RunDataset(folder, "configs/KITTI04-12.yaml", true, 25);
  const DatasetRun b = RunDataset(folder, "configs/KITTI04-12.yaml", true, 25);
  ASSERT_EQ(a.estimate.size(), b.estimate.size());
  for (size_t i = 0; i < a.estimate.size(); ++i) {
    EXPECT_EQ(a.estimate.poses[i].Matrix(), b.estimate.poses[i].Matrix()) << "frame " << i;
  }
  EXPECT_EQ(a.summary.keyframes, b.summary.keyframes);
  EXPECT_EQ(a.summary.map_points, b.summary.map_points);
}

// Threaded runs of the first 20 frames reach 0.018-0.026 m (free-running, whatever the machine's
// load, thanks to the weak tracker's keyframes; see the next test).
constexpr double kMaxThreadedAteRmse = 0.05;

TEST(SystemKitti, ThreadedMappingTracksEveryFrame) {
  MOSLAM_SHARED_OR_SKIP(folder, "data/kitti/06_000000-000050");
  const DatasetRun run = RunDataset(folder, "configs/KITTI04-12.yaml", false, 20);
  EXPECT_EQ(run.frames_ok, 20);
  EXPECT_LT(run.ate_rmse, kMaxThreadedAteRmse);
  std::printf("KITTI 06 0-19 threaded: ATE RMSE %.4f m, %d keyframes\n", run.ate_rmse,
              run.summary.keyframes);
}

// Local mapping starved of CPU, as on a loaded machine: the whole run on one core with mapping at
// the lowest priority, so it runs only while tracking waits. Tracking then finds at most three
// keyframes queued (ORB-SLAM2's limit) and, before the tracker queued a weak frame's keyframe
// regardless, tracked on a thinning map: 5-6 keyframes instead of 12-13, a few dozen inliers,
// ATE 0.045-0.18 m (keyframes themselves stayed at 0.015 m). This is what failed CI once.
TEST(SystemKitti, StarvedMappingStillTracksAccurately) {
#ifdef __linux__
  MOSLAM_SHARED_OR_SKIP(folder, "data/kitti/06_000000-000050");
  cpu_set_t saved;
  ASSERT_EQ(sched_getaffinity(0, sizeof(saved), &saved), 0);
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(sched_getcpu(), &one);
  ASSERT_EQ(sched_setaffinity(0, sizeof(one), &one), 0);  // threads started now inherit it
  // The test thread gets all CPUs back however the run ends (the other tests run after it).
  const std::unique_ptr<cpu_set_t, void (*)(cpu_set_t*)> restore(
      &saved, [](cpu_set_t* set) { sched_setaffinity(0, sizeof(*set), set); });
  const DatasetRun run = RunDataset(folder, "configs/KITTI04-12.yaml", false, 20, "",
                                    [](SystemOptions* o) { o->background_nice = 19; });
  EXPECT_EQ(run.frames_ok, 20);
  EXPECT_GE(run.summary.keyframes, 9);
  EXPECT_LT(run.ate_rmse, kMaxThreadedAteRmse);
  std::printf("KITTI 06 0-19 mapping starved: ATE RMSE %.4f m, %d keyframes\n", run.ate_rmse,
              run.summary.keyframes);
#else
  GTEST_SKIP() << "needs Linux (thread affinity and per-thread nice values)";
#endif
}

// A frame that cannot be tracked (a black image pair, as from a covered lens) is reported lost
// with a reason; the run goes on and tracking resumes from the reference keyframe.
TEST(SystemKitti, LostFrameIsReportedAndTrackingResumes) {
  MOSLAM_SHARED_OR_SKIP(folder, "data/kitti/06_000000-000050");
  const io::Sequence sequence = io::ReadDataset(folder);
  SystemOptions options;
  options.sensor = sequence.sensor;
  options.settings = io::LoadOrbSlamSettings("configs/KITTI04-12.yaml", sequence.sensor);
  options.deterministic = true;
  System system(options);
  std::vector<FrameReport> reports;
  for (int i = 0; i < 12; ++i) {
    const io::FrameImages images = io::LoadFrameImages(sequence.frames[i], io::ColourMode::kGrey);
    FrameInput input;
    input.timestamp = sequence.frames[i].timestamp;
    input.image = images.left;
    input.right = images.right;
    if (i == 8) {
      input.image = cv::Mat::zeros(images.left.size(), CV_8UC1);
      input.right = cv::Mat::zeros(images.right.size(), CV_8UC1);
    }
    reports.push_back(system.Track(input));
  }
  system.Finish();
  EXPECT_EQ(reports[7].state, TrackingState::kOk);
  EXPECT_EQ(reports[8].state, TrackingState::kLost);
  EXPECT_FALSE(reports[8].reason.empty());
  EXPECT_FALSE(reports[8].T_world_cam.has_value());
  EXPECT_EQ(reports[9].state, TrackingState::kOk) << reports[9].reason;
  EXPECT_EQ(reports[11].state, TrackingState::kOk) << reports[11].reason;
  EXPECT_EQ(system.Summary().lost_frames, 1);
  EXPECT_EQ(system.CameraTrajectory().size(), 11u);  // the lost frame has no pose
}

}  // namespace
}  // namespace moslam::slam
