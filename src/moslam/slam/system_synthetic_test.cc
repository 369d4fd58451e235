// End-to-end on a synthetic RGB-D sequence (moslam synth, docs/SYNTH.md): an office with people
// walking in front of a camera moving along x, y and z, exact ground truth. The people are masked
// out with the sequence's moving-object masks, as the paper's segmentation would do.
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/slam/run_dataset.h"
#include "moslam/synth/generator.h"
#include "moslam/testing/sanitizer.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

// The first `frames` frames of a generator preset into `dir`.
void Generate(const std::string& preset, uint64_t seed, int frames, const testing::TempDir& dir) {
  synth::GeneratorOptions generator;
  generator.preset = preset;
  generator.seed = seed;
  generator.out = dir.path();
  generator.frames = frames;
  generator.progress = false;
  synth::GenerateSequence(generator);
}

TEST(SystemSynthetic, RgbdWithMovingMasksTracksEveryFrameAndBeatsUnmasked) {
  const testing::TempDir dir;
  Generate("w_xyz", 3, 60, dir);  // 2 s, ~0.1 m of camera motion
  const DatasetRun run = RunDataset(dir.path(), dir.path() + "/settings.yaml",
                                    /*deterministic=*/true, 0, "moving");
  ASSERT_EQ(run.reports.size(), 60u);
  EXPECT_EQ(run.frames_ok, 60);
  // Kinect-like depth noise is a few millimetres at 1-4 m; a working tracker stays within a
  // few centimetres, a broken one drifts by the size of the motion.
  EXPECT_GE(run.ate_rmse, 0.0);
  EXPECT_LT(run.ate_rmse, 0.03);
  std::printf("synthetic w_xyz 60 frames: ATE RMSE %.4f m, %d keyframes\n", run.ate_rmse,
              run.summary.keyframes);

  // Without masks the walkers, who cross close in front of the camera and cover up to half of the
  // view, pull the tracker along (what breaks ORB-SLAM2 on TUM's walking sequences): the error
  // grows to 4-30 cm, far above the masked run's. Measured on seeds 1-4 (docs/SYNTH.md).
  const DatasetRun unmasked =
      RunDataset(dir.path(), dir.path() + "/settings.yaml", /*deterministic=*/true, 0, "");
  ASSERT_EQ(unmasked.reports.size(), 60u);
  EXPECT_GT(unmasked.ate_rmse, 5.0 * run.ate_rmse);  // measured 18-65x, seeds 1-4
  std::printf("synthetic w_xyz 60 frames without masks: ATE RMSE %.4f m\n", unmasked.ate_rmse);
}

// The deterministic stand-in for the mapping thread (SystemOptions::deterministic_mapping_frames,
// issue 28): with local mapping taking 4 frames per keyframe, keyframes wait in its queue and
// those mapped while others wait run no local bundle adjustment, as in a threaded run; the run
// stays as accurate and is still repeatable to the last bit.
TEST(SystemSynthetic, DeterministicMappingQueueSkipsAdjustmentsAndStaysRepeatable) {
  const testing::TempDir dir;
  Generate("w_xyz", 3, 60, dir);
  const auto queued = [](SystemOptions* o) { o->deterministic_mapping_frames = 4; };
  const std::string settings = dir.path() + "/settings.yaml";
  const DatasetRun at_once =
      RunDataset(dir.path(), settings, true, 0, "moving",
                 [](SystemOptions* o) { o->deterministic_mapping_frames = 1; });
  const DatasetRun first = RunDataset(dir.path(), settings, true, 0, "moving", queued);
  const DatasetRun second = RunDataset(dir.path(), settings, true, 0, "moving", queued);
  const auto created = [](const DatasetRun& run) {
    int n = 0;
    for (const FrameReport& r : run.reports) n += r.new_keyframe ? 1 : 0;
    return n;
  };
  std::printf(
      "w_xyz seed 3, 60 frames: mapped at once: %d keyframes, %d local BAs, ATE %.4f m; 4 frames "
      "a keyframe: %d keyframes, %d local BAs, ATE %.4f m\n",
      created(at_once), at_once.summary.local_bundle_adjustments, at_once.ate_rmse, created(first),
      first.summary.local_bundle_adjustments, first.ate_rmse);
  // Mapped at once, every keyframe is adjusted (the first two form the map).
  EXPECT_EQ(at_once.summary.mapping_steps, created(at_once));
  EXPECT_GE(at_once.summary.local_bundle_adjustments, created(at_once) - 2);
  // Every keyframe is mapped by the end (but those culled while they waited), fewer are adjusted.
  EXPECT_EQ(first.frames_ok, 60);
  EXPECT_LE(first.summary.mapping_steps, created(first));
  EXPECT_GT(first.summary.mapping_steps, created(first) / 2);
  EXPECT_GE(first.summary.local_bundle_adjustments, 1);
  EXPECT_LT(first.summary.local_bundle_adjustments, at_once.summary.local_bundle_adjustments);
  EXPECT_GE(first.ate_rmse, 0.0);
  EXPECT_LT(first.ate_rmse, 0.03);
  EXPECT_EQ(created(second), created(first));
  EXPECT_EQ(second.summary.local_bundle_adjustments, first.summary.local_bundle_adjustments);
  EXPECT_EQ(second.ate_rmse, first.ate_rmse);
  SystemOptions bad;
  bad.deterministic_mapping_frames = -1;
  EXPECT_THROW(bad.Check(), InputError);
  bad = {};
  bad.deterministic_mapping_ms_per_observation = -1.0;
  EXPECT_THROW(bad.Check(), InputError);
}

// Imperfect masks (issue 24): the generator's exact masks, but every third frame has none (a
// network's missed frames) and the others lose 4 px all round and everything within 40 px of the
// image's border (people entering and leaving). With the mechanisms of slam/movable_points.h,
// mask_propagation.h and moving_keypoints.h the run stays within twice the exact masks' error.
TEST(SystemSynthetic, DegradedMasksStayWithinTwiceTheExactMasksError) {
  MOSLAM_SKIP_UNDER_SANITIZER(
      "three deterministic 90-frame runs; the unit tests of each "
      "mechanism run under the sanitizers");
  const testing::TempDir dir;
  Generate("w_xyz", 4, 90, dir);
  const auto damage = [](size_t frame, const cv::Mat& mask) -> cv::Mat {
    if (frame % 3 == 2) return cv::Mat::zeros(mask.size(), CV_8UC1);
    cv::Mat out;
    cv::erode(mask, out, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(9, 9)));
    const int b = 40;
    out.rowRange(0, b).setTo(0);
    out.rowRange(out.rows - b, out.rows).setTo(0);
    out.colRange(0, b).setTo(0);
    out.colRange(out.cols - b, out.cols).setTo(0);
    return out;
  };
  const std::string settings = dir.path() + "/settings.yaml";
  const DatasetRun exact = RunDataset(dir.path(), settings, true, 0, "moving");
  const DatasetRun degraded =
      RunDataset(dir.path(), settings, true, 0, "moving", {}, false, damage);
  const DatasetRun bare = RunDataset(
      dir.path(), settings, true, 0, "moving",
      [](SystemOptions* o) {
        o->movable_evidence = o->free_space_evidence = o->moving_keypoint_check = false;
        o->static_scores = o->moving_regions = o->pose_consensus = false;
        o->mask_margin_px = o->mask_propagation_frames = o->mask_completion_px = 0;
      },
      false, damage);
  std::printf(
      "w_xyz seed 4, 90 frames: exact masks %.4f m, degraded %.4f m (%d points erased), "
      "degraded without the mechanisms %.4f m\n",
      exact.ate_rmse, degraded.ate_rmse, degraded.summary.movable_points_erased, bare.ate_rmse);
  EXPECT_EQ(degraded.frames_ok, 90);
  EXPECT_GT(degraded.summary.movable_points_erased, 0);
  EXPECT_LT(degraded.ate_rmse, 2.0 * exact.ate_rmse);  // measured 0.0065 against 0.0049 m
  // The damage matters: without the mechanisms the same masks give 0.098 m (measured; 0.0143 m
  // with only the geometric ones of static_scores.h, moving_regions.h and pose_consensus.h).
  EXPECT_GT(bare.ate_rmse, 3.0 * degraded.ate_rmse);
}

// A street of identical houses (issue 32's aliasing ring, docs/SYNTH.md) at the end of a corner.
// Found on seed 3: at frame 233 the yaw rate drops from 16 deg/s to 0 at once, the
// constant-velocity prediction is ~20 px off, and the motion model finds 122 of the last frame's
// 576 points, among facades of identical windows. Taking its pose put the camera 1.7 m back, one
// window over, and the next frames followed (4 m off by frame 236, 13 m by 240). With the
// cross-check against the reference keyframe the camera stays on the street. Issue 29's stereo
// matcher changed which sequences trip it: seed 3 no longer does (0.088 m without the check),
// seed 4 does (1.95 m without it, 0.024 m with it, measured).
TEST(SystemSynthetic, AliasedFacadesAtTheEndOfACornerDoNotMoveTheCamera) {
  MOSLAM_SKIP_UNDER_SANITIZER("two deterministic 240-frame stereo runs of 1226 x 370 images");
  const testing::TempDir dir;
  Generate("street_repeat_loop", 4, 240, dir);
  const std::string settings = dir.path() + "/settings.yaml";
  const DatasetRun checked = RunDataset(dir.path(), settings, true, 0, "");
  const DatasetRun unchecked = RunDataset(dir.path(), settings, true, 0, "",
                                          [](SystemOptions* o) { o->motion_cross_check = false; });
  std::printf("street_repeat_loop seed 4, 240 frames: ATE %.4f m, without the cross-check %.4f m\n",
              checked.ate_rmse, unchecked.ate_rmse);
  EXPECT_EQ(checked.frames_ok, 240);
  EXPECT_GE(checked.ate_rmse, 0.0);
  EXPECT_LT(checked.ate_rmse, 0.3);
  // The case is the one described: without the check the camera leaves the street.
  EXPECT_GT(unchecked.ate_rmse, 0.5);  // measured 1.95 m
}

}  // namespace
}  // namespace moslam::slam
