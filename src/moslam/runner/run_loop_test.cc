// The run loop with a fake tracker on tiny TUM- and KITTI-layout sequences: output files and
// their formats, frame ranges, and clean stops at the end and on errors in either thread.
#include "moslam/runner/run_loop.h"
#include "moslam/runner/mask_damage.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "moslam/eval/trajectory_io.h"
#include "moslam/io/dataset.h"
#include "moslam/runner/mask_damage.h"
#include "moslam/runner/outputs.h"
#include "moslam/runner/test_sequences.h"
#include "moslam/testing/error_of.h"
#include "moslam/util/strings.h"

namespace moslam::runner {
namespace {

namespace fs = std::filesystem;
using ::moslam::testing::ErrorOf;
using test::FakeTracker;
using ::testing::HasSubstr;
using ::testing::Not;

std::vector<std::string> Lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

size_t FieldCount(const std::string& line) { return SplitFields(line).size(); }

RunOptions Quiet() {
  RunOptions options;
  options.progress = false;
  return options;
}

RunDescription Describe(const io::Sequence& seq, const MaskSource& masks) {
  RunDescription d;
  d.dataset_path = seq.root;
  d.format = io::DetectDatasetFormat(seq.root).value();
  d.sensor = seq.sensor;
  d.settings_path = "none";
  d.mask_source = masks.Describe();
  return d;
}

TEST(RunLoopTest, TumRunWritesEveryOutputInItsFormat) {
  testing::TempDir data, out;
  test::MakeTum(data, 6);
  const io::Sequence seq = io::ReadDataset(data.path());
  FakeTracker tracker;
  tracker.lost = [](int i) { return i == 3; };
  const auto masks = MakeMaskSource({}, seq);
  const RunResult result = RunSequence(seq, tracker, *masks, Quiet());
  EXPECT_TRUE(tracker.finished);
  ASSERT_EQ(result.frames.size(), 6u);
  EXPECT_TRUE(tracker.had_depth[0]);
  EXPECT_FALSE(tracker.had_right[0]);
  EXPECT_TRUE(tracker.masks[0].empty());

  const std::string text = WriteRunOutputs(seq, result, Describe(seq, *masks), out.path());
  const fs::path dir(out.path());
  // TUM camera trajectory: one line per tracked frame, 8 fields, ORB-SLAM2's decimals.
  const auto camera = Lines((dir / "CameraTrajectory.txt").string());
  ASSERT_EQ(camera.size(), 5u);
  for (const std::string& line : camera) EXPECT_EQ(FieldCount(line), 8u) << line;
  EXPECT_THAT(camera[0], ::testing::StartsWith(test::Stamp(0) + " "));
  EXPECT_EQ(SplitFields(camera[0])[1].size(), std::string("100.000000000").size());
  const eval::Trajectory read = eval::ReadTum((dir / "CameraTrajectory.txt").string());
  EXPECT_NEAR(read.poses[4].translation().z(), test::PoseAt(test::StampValue(5)).translation().z(),
              1e-8);
  EXPECT_FALSE(fs::exists(dir / "CameraTrajectory_kitti.txt"));
  // Keyframes: frames 0, 2, 4; seven decimals.
  const auto keyframes = Lines((dir / "KeyFrameTrajectory.txt").string());
  ASSERT_EQ(keyframes.size(), 3u);
  EXPECT_EQ(FieldCount(keyframes[1]), 8u);
  EXPECT_EQ(SplitFields(keyframes[0])[1].size(), std::string("100.0000000").size());
  // Per-frame log.
  const auto csv = Lines((dir / "frames.csv").string());
  ASSERT_EQ(csv.size(), 7u);
  EXPECT_EQ(csv[0], kFramesCsvHeader);
  EXPECT_EQ(SplitFields(csv[0], true).size(), 26u);
  EXPECT_EQ(std::count(csv[1].begin(), csv[1].end(), ','), 25);  // as many fields as the header
  // The last column: the process's resident memory after the frame, MiB (a test binary holds
  // more than 1 MiB and less than 64 GiB).
  const double rss_mb = std::stod(csv[1].substr(csv[1].rfind(',') + 1));
  EXPECT_GT(rss_mb, 1.0);
  EXPECT_LT(rss_mb, 65536.0);
  EXPECT_THAT(csv[1], ::testing::StartsWith("0," + test::Stamp(0) + ",ok,,100,80,60,1,1.000,"));
  EXPECT_THAT(csv[4], HasSubstr(",lost,\"too few matches, said the fake\",103,"));
  // Summary with the ATE against groundtruth.txt: the fake reports the true poses.
  std::ifstream in((dir / "summary.json").string());
  const nlohmann::json summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["frames"], 6);
  EXPECT_EQ(summary["tracked"], 5);
  EXPECT_EQ(summary["lost"], 1);
  EXPECT_EQ(summary["keyframes"], 3);
  EXPECT_EQ(summary["map_points"], 21);
  EXPECT_DOUBLE_EQ(summary["times_ms"]["extract_ms"]["median"].get<double>(), 3.5);
  EXPECT_DOUBLE_EQ(summary["times_ms"]["extract_ms"]["p90"].get<double>(), 5.5);
  // The per-frame breakdown: extraction 1 + i ms for i = 0..5 (median 3.5), no segmentation.
  EXPECT_DOUBLE_EQ(summary["breakdown_median_ms"]["extraction"].get<double>(), 3.5);
  EXPECT_DOUBLE_EQ(summary["breakdown_median_ms"]["segmentation"].get<double>(), 0.0);
  EXPECT_TRUE(summary["breakdown_median_ms"].contains("mapping_per_frame"));
  EXPECT_EQ(summary["mask_source"], "none");
  ASSERT_TRUE(summary["ate"].is_object()) << summary.dump(2);
  EXPECT_EQ(summary["ate"]["translation_m"]["count"], 5);
  EXPECT_LT(summary["ate"]["translation_m"]["rmse"].get<double>(), 1e-6);
  EXPECT_TRUE(fs::exists(dir / "trajectory.png"));
  EXPECT_EQ(summary["end"]["status"], "completed");
  EXPECT_EQ(summary["end"]["message"], "");
  EXPECT_TRUE(summary["output_errors"].empty());
  EXPECT_THAT(text, HasSubstr("5 tracked, 1 lost"));
  EXPECT_THAT(text, HasSubstr("ATE"));
  EXPECT_THAT(text, Not(HasSubstr("ended")));
  // Nothing but the outputs: no temporary file is left.
  for (const auto& entry : fs::directory_iterator(dir)) {
    EXPECT_THAT(entry.path().string(), Not(HasSubstr(".tmp"))) << entry.path();
  }
}

TEST(RunLoopTest, KittiRunAddsKittiTrajectoryAndEvaluatesByTimesTxt) {
  testing::TempDir data, out;
  test::MakeKitti(data, 5);
  const io::Sequence seq = io::ReadDataset(data.path());
  ASSERT_EQ(seq.sensor, io::SensorType::kStereo);
  FakeTracker tracker;
  const auto masks = MakeMaskSource({}, seq);
  RunOptions options = Quiet();
  options.frames = ParseFrameRange("1:");
  const RunResult result = RunSequence(seq, tracker, *masks, options);
  ASSERT_EQ(result.frames.size(), 4u);
  EXPECT_EQ(result.frames.front().index, 1);
  EXPECT_TRUE(tracker.had_right[0]);
  EXPECT_FALSE(tracker.had_depth[0]);
  WriteRunOutputs(seq, result, Describe(seq, *masks), out.path());
  const fs::path dir(out.path());
  const auto kitti = Lines((dir / "CameraTrajectory_kitti.txt").string());
  ASSERT_EQ(kitti.size(), 4u);
  for (const std::string& line : kitti) EXPECT_EQ(FieldCount(line), 12u) << line;
  const eval::Trajectory read = eval::ReadKitti((dir / "CameraTrajectory_kitti.txt").string());
  EXPECT_NEAR(read.poses[3].translation().x(), test::PoseAt(0.4).translation().x(), 1e-8);
  EXPECT_EQ(Lines((dir / "CameraTrajectory.txt").string()).size(), 4u);
  std::ifstream in((dir / "summary.json").string());
  const nlohmann::json summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["frame_range"], nlohmann::json::array({1, 5}));
  ASSERT_TRUE(summary["ate"].is_object()) << summary.dump(2);
  EXPECT_EQ(summary["ate"]["translation_m"]["count"], 4);  // frames 1-4 matched by times.txt
  EXPECT_LT(summary["ate"]["translation_m"]["rmse"].get<double>(), 1e-6);
}

// The shared KITTI 06 excerpt through the loading thread, with a tracker that answers poses.txt:
// real images load as stereo pairs and the summary's ATE, matched through times.txt, is ~0.
TEST(RunLoopTest, SharedKittiExcerptWithGroundTruthTracker) {
  MOSLAM_SHARED_OR_SKIP(kitti, "data/kitti/06_000000-000050");
  testing::TempDir out;
  const io::Sequence seq = io::ReadDataset(kitti);
  const eval::Trajectory gt = eval::ReadKitti(*seq.ground_truth_path);
  ASSERT_EQ(gt.size(), seq.size());
  FakeTracker tracker;
  tracker.pose = [&gt](int i, double) { return gt.poses[i]; };
  const auto masks = MakeMaskSource({}, seq);
  const RunResult result = RunSequence(seq, tracker, *masks, Quiet());
  ASSERT_EQ(result.frames.size(), seq.size());
  EXPECT_EQ(tracker.images[0].type(), CV_8UC1);
  EXPECT_EQ(tracker.images[0].size(), cv::Size(1226, 370));
  EXPECT_TRUE(tracker.had_right[50]);
  WriteRunOutputs(seq, result, Describe(seq, *masks), out.path());
  EXPECT_EQ(Lines(out.path() + "/CameraTrajectory_kitti.txt").size(), seq.size());
  std::ifstream in(out.path() + "/summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  ASSERT_TRUE(summary["ate"].is_object());
  EXPECT_EQ(summary["ate"]["translation_m"]["count"], 51);
  EXPECT_LT(summary["ate"]["translation_m"]["rmse"].get<double>(), 1e-5);
}

TEST(RunLoopTest, SkippedFramesNeverReachTheTracker) {
  testing::TempDir data;
  test::MakeKitti(data, 6);
  const io::Sequence seq = io::ReadDataset(data.path());
  const auto masks = MakeMaskSource({}, seq);
  FakeTracker tracker;
  RunOptions options = Quiet();
  options.frames = ParseFrameRange("1:");
  options.skip = ParseFrameRange("2:4", "--skip-frames");
  const RunResult result = RunSequence(seq, tracker, *masks, options);
  ASSERT_EQ(result.frames.size(), 3u);
  EXPECT_EQ(result.frames[0].index, 1);
  EXPECT_EQ(result.frames[1].index, 4);
  EXPECT_EQ(result.frames[2].index, 5);
  EXPECT_EQ(result.skipped, 2u);
  EXPECT_THAT(ErrorOf([] { ParseFrameRange("4:2", "--skip-frames"); }),
              HasSubstr("--skip-frames: the range '4:2' is empty"));
}

// A mask over the whole image on every frame it is asked for.
class FullMasks : public MaskSource {
 public:
  FrameMask MaskFor(const io::FrameEntry&, const cv::Size& size) const override {
    FrameMask mask;
    mask.mask = cv::Mat(size, CV_8UC1, cv::Scalar(255));
    mask.fraction = 1.0;
    return mask;
  }
  std::string Describe() const override { return "full"; }
};

TEST(RunLoopTest, SegmentEveryKRunsTheSourceOnEveryKthFrameOnly) {
  testing::TempDir data;
  test::MakeKitti(data, 7);
  const io::Sequence seq = io::ReadDataset(data.path());
  FullMasks masks;
  FakeTracker tracker;
  RunOptions options = Quiet();
  options.frames = ParseFrameRange("1:");
  options.segment_every = 3;
  const RunResult result = RunSequence(seq, tracker, masks, options);
  ASSERT_EQ(tracker.masks.size(), 6u);
  for (size_t k = 0; k < 6; ++k) {
    // Frames 1 and 4: counted from the range's first frame.
    EXPECT_EQ(tracker.masks[k].empty(), k % 3 != 0) << "frame " << k + 1;
    EXPECT_EQ(result.frames[k].segmented, k % 3 == 0);
  }
  // Damage on top: every frame missed.
  const auto damaged =
      MakeDamagedMaskSource(std::make_unique<FullMasks>(), ParseMaskDamage("miss=1"));
  FakeTracker second;
  options.segment_every = 1;
  RunSequence(seq, second, *damaged, options);
  for (const cv::Mat& mask : second.masks) EXPECT_EQ(cv::countNonZero(mask), 0);
  options.segment_every = -1;
  EXPECT_THROW(RunSequence(seq, tracker, masks, options), InputError);
}

// A source that takes 40 ms a frame.
class SlowMasks : public FullMasks {
 public:
  FrameMask MaskFor(const io::FrameEntry& entry, const cv::Size& size) const override {
    std::this_thread::sleep_for(std::chrono::milliseconds(40));
    return FullMasks::MaskFor(entry, size);
  }
};

// --segment-every auto: the fake tracker says it takes 2-31 ms a frame, the source takes 40, so
// once both are measured the source runs on every second to fourth frame only; the frames
// segmented before the first tracking time arrived (the stages run a few frames ahead) are all
// segmented.
TEST(RunLoopTest, SegmentEveryAutoSkipsFramesWhenTheSourceIsSlowerThanTracking) {
  testing::TempDir data;
  test::MakeKitti(data, 30);
  const io::Sequence seq = io::ReadDataset(data.path());
  SlowMasks masks;
  FakeTracker tracker;
  RunOptions options = Quiet();
  options.segment_every = 0;
  const RunResult result = RunSequence(seq, tracker, masks, options);
  ASSERT_EQ(result.frames.size(), 30u);
  int segmented = 0;
  for (size_t k = 0; k < 30; ++k) {
    segmented += result.frames[k].segmented ? 1 : 0;
    EXPECT_EQ(tracker.masks[k].empty(), !result.frames[k].segmented) << "frame " << k;
    if (k >= 20 && result.frames[k].segmented) {
      EXPECT_FALSE(result.frames[k - 1].segmented) << "frame " << k;
    }
  }
  EXPECT_TRUE(result.frames[0].segmented);
  EXPECT_LT(segmented, 25);
  EXPECT_GE(segmented, 30 / 4);
}

TEST(RunLoopTest, FrameRangeSelectsAndIsChecked) {
  testing::TempDir data;
  test::MakeKitti(data, 5);
  const io::Sequence seq = io::ReadDataset(data.path());
  const auto masks = MakeMaskSource({}, seq);
  FakeTracker tracker;
  RunOptions options = Quiet();
  options.frames = ParseFrameRange("1:3");
  const RunResult result = RunSequence(seq, tracker, *masks, options);
  ASSERT_EQ(result.frames.size(), 2u);
  EXPECT_EQ(result.frames[1].index, 2);
  options.frames = ParseFrameRange("2:9");
  EXPECT_THAT(ErrorOf([&] { RethrowFailure(RunSequence(seq, tracker, *masks, options)); }),
              HasSubstr("outside the sequence's 5 frames"));
}

TEST(RunLoopTest, ParseFrameRangeForms) {
  EXPECT_EQ(ParseFrameRange("3:7").first, 3u);
  EXPECT_EQ(ParseFrameRange("3:7").last, 7u);
  EXPECT_FALSE(ParseFrameRange("3:").last.has_value());
  EXPECT_EQ(ParseFrameRange(":7").first, 0u);
  EXPECT_THAT(ErrorOf([] { ParseFrameRange("7"); }), HasSubstr("expected A:B"));
  EXPECT_THAT(ErrorOf([] { ParseFrameRange("5:5"); }), HasSubstr("empty"));
  EXPECT_THAT(ErrorOf([] { ParseFrameRange("-1:5"); }), HasSubstr("'-1'"));
}

TEST(RunLoopTest, LoaderErrorEndsTheRunAfterTheEarlierFrames) {
  testing::TempDir data;
  test::MakeKitti(data, 12);
  const io::Sequence seq = io::ReadDataset(data.path());
  const std::string missing = data.path() + "/image_1/000007.png";
  fs::remove(missing);  // the reader saw it; loading frame 7 fails
  const auto masks = MakeMaskSource({}, seq);
  FakeTracker tracker;
  RunOptions options = Quiet();
  options.queue_capacity = 1;
  const RunResult result = RunSequence(seq, tracker, *masks, options);
  EXPECT_EQ(result.end, RunEnd::kFailed);
  EXPECT_THAT(result.end_message, HasSubstr(missing));
  EXPECT_THAT(ErrorOf([&] { RethrowFailure(result); }), HasSubstr(missing));
  EXPECT_EQ(tracker.masks.size(), 7u);  // frames 0-6 were tracked, in order, before the error
  // ... and keep their poses: the tracker was finished as at the end of the data.
  EXPECT_TRUE(tracker.finished);
  EXPECT_EQ(result.frames.size(), 7u);
  EXPECT_EQ(result.camera.size(), 7u);
}

TEST(RunLoopTest, TrackerErrorStopsTheLoaderWithoutDeadlock) {
  testing::TempDir data;
  test::MakeKitti(data, 12);
  const io::Sequence seq = io::ReadDataset(data.path());
  const auto masks = MakeMaskSource({}, seq);
  FakeTracker tracker;
  tracker.before_track = [](int i) {
    if (i == 2) throw std::runtime_error("tracker failed");
  };
  RunOptions options = Quiet();
  options.queue_capacity = 1;  // the loader is blocked on a full queue when the tracker throws
  const RunResult result = RunSequence(seq, tracker, *masks, options);
  EXPECT_EQ(result.end, RunEnd::kFailed);
  EXPECT_EQ(result.end_message, "tracker failed");
  EXPECT_THROW(RethrowFailure(result), std::runtime_error);
  EXPECT_EQ(tracker.masks.size(), 2u);
  EXPECT_EQ(result.frames.size(), 2u);
}

// Issue 31: images of another size than the settings' were tracked with intrinsics for the
// wrong size; now the first such image fails the run, named with both sizes.
TEST(RunLoopTest, AnImageOfAnotherSizeThanTheSettingsIsNamed) {
  testing::TempDir data;
  test::MakeTum(data, 6);
  const std::string odd = data.path() + "/rgb/" + test::Stamp(3) + ".png";
  test::WriteImage(data, "rgb/" + test::Stamp(3) + ".png", cv::Mat(8, 8, CV_8UC1, cv::Scalar(9)));
  const io::Sequence seq = io::ReadDataset(data.path());
  const auto masks = MakeMaskSource({}, seq);
  RunOptions options = Quiet();
  options.colour = io::ColourMode::kGrey;
  options.image_size = cv::Size(test::kCols, test::kRows);
  options.image_size_source = "settings.yaml";
  // Its depth map too, so that the pair agrees and only the settings' size is wrong.
  test::WriteImage(data, "depth/" + test::Stamp(3) + ".png",
                   cv::Mat(8, 8, CV_16UC1, cv::Scalar(5000)));
  FakeTracker tracker;
  EXPECT_THAT(ErrorOf([&] { RethrowFailure(RunSequence(seq, tracker, *masks, options)); }),
              ::testing::AllOf(HasSubstr(odd), HasSubstr("frame 3"), HasSubstr("8x8"),
                               HasSubstr("settings.yaml"), HasSubstr("24x16")));
  EXPECT_EQ(tracker.masks.size(), 3u);
  // The whole sequence at another size fails at its first frame.
  FakeTracker other;
  options.image_size = cv::Size(2 * test::kCols, 2 * test::kRows);
  EXPECT_THAT(ErrorOf([&] { RethrowFailure(RunSequence(seq, other, *masks, options)); }),
              ::testing::AllOf(HasSubstr(data.path() + "/rgb/" + test::Stamp(0) + ".png"),
                               HasSubstr("48x32")));
  EXPECT_TRUE(other.masks.empty());
}

TEST(RunLoopTest, AnInputErrorOfTheTrackerNamesTheFrameAndImage) {
  testing::TempDir data;
  test::MakeKitti(data, 5);
  const io::Sequence seq = io::ReadDataset(data.path());
  const auto masks = MakeMaskSource({}, seq);
  FakeTracker tracker;
  tracker.before_track = [](int i) {
    if (i == 2) ThrowInput("ORB extractor: the image is 16x16, smaller than the minimum 64x64");
  };
  EXPECT_THAT(ErrorOf([&] { RethrowFailure(RunSequence(seq, tracker, *masks, Quiet())); }),
              ::testing::AllOf(HasSubstr(data.path() + "/image_0/000002.png"), HasSubstr("frame 2"),
                               HasSubstr("smaller than the minimum")));
}

TEST(RunLoopTest, ABrokenGroundTruthIsFoundBeforeTheRun) {
  testing::TempDir data;
  test::MakeTum(data, 3);
  const io::Sequence seq = io::ReadDataset(data.path());
  EXPECT_NO_THROW(CheckGroundTruth(seq));
  const std::string gt =
      data.Write("groundtruth.txt", "100.0 1 2 3 0 0 0 1\n100.1 1 2 x 0 0 0 1\n");
  EXPECT_THAT(ErrorOf([&] { CheckGroundTruth(seq); }), HasSubstr(gt + ":2:"));
  data.Write("groundtruth.txt", "# nothing\n");
  EXPECT_THAT(ErrorOf([&] { CheckGroundTruth(seq); }), HasSubstr(gt));
}

TEST(RunLoopTest, RealtimeIsNeverAheadOfTheTimestamps) {
  testing::TempDir data;
  test::MakeKitti(data, 4);  // 0.3 s of data
  const io::Sequence seq = io::ReadDataset(data.path());
  const auto masks = MakeMaskSource({}, seq);
  FakeTracker tracker;
  RunOptions options = Quiet();
  options.realtime = true;
  const RunResult result = RunSequence(seq, tracker, *masks, options);
  ASSERT_EQ(result.frames.size(), 4u);
  // sleep_until never wakes early, so the run lasts at least the data's span.
  EXPECT_GE(result.wall_s, 0.3);
}

TEST(RunLoopTest, PercentileIsNumpys) {
  EXPECT_DOUBLE_EQ(Percentile({}, 90), 0.0);
  EXPECT_DOUBLE_EQ(Percentile({5.0}, 90), 5.0);
  EXPECT_DOUBLE_EQ(Percentile({4, 1, 3, 2}, 50), 2.5);
  EXPECT_DOUBLE_EQ(Percentile({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, 90), 10.0);
}

}  // namespace
}  // namespace moslam::runner
