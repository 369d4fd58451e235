// Live runs (RunLive, live_capture.h) driven by fake sources: a source slower than tracking has
// every frame tracked; a faster one has frames dropped and counted with the queue bounded; the
// stop flag and a failing device end the run cleanly. The sources and the fake tracker hand
// over through condition variables (who waits for whom is the test), never by sleeping.
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <optional>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "moslam/runner/outputs.h"
#include "moslam/runner/run_loop.h"
#include "moslam/runner/test_sequences.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::runner {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

double StampOf(int i) { return 100.0 + 0.1 * i; }
int IndexOf(double stamp) { return static_cast<int>(std::lround((stamp - 100.0) / 0.1)); }

// An RGB-D source of `frames` frames (-1: endless). Before delivering frame i it runs
// `before_grab(i)`, where a test makes it wait for the tracker. Counts what it delivered.
class FakeSource : public io::LiveSource {
 public:
  explicit FakeSource(int frames) : frames_(frames) {}
  std::function<void(int)> before_grab = [](int) {};
  std::optional<int> fail_at;  // Grab() of this frame throws, as an unplugged camera
  cv::Size size{test::kCols, test::kRows};

  std::optional<io::LiveFrame> Grab() override {
    const int i = next_;
    if (frames_ >= 0 && i >= frames_) {
      Delivered(i, true);
      return std::nullopt;
    }
    before_grab(i);
    if (fail_at && i == *fail_at) {
      Delivered(i, true);
      ThrowInFile(name(), "delivered no frame (unplugged?)");
    }
    io::LiveFrame frame;
    frame.timestamp = StampOf(i);
    frame.images.left = cv::Mat(size, CV_8UC3, cv::Scalar(i % 256, 0, 0));
    frame.images.depth = cv::Mat(size, CV_32FC1, cv::Scalar(1.0f));
    ++next_;
    Delivered(i + 1, false);
    return frame;
  }
  io::SensorType sensor() const override { return io::SensorType::kRgbD; }
  std::string name() const override { return "fake0"; }
  cv::Size image_size() const override { return size; }

  // Waits until `count` frames were delivered or the source ended.
  void WaitDelivered(int count) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return delivered_ >= count || ended_; });
  }
  int delivered() {
    std::lock_guard<std::mutex> lock(mutex_);
    return delivered_;
  }

 private:
  void Delivered(int count, bool ended) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      delivered_ = count;
      ended_ = ended;
    }
    changed_.notify_all();
  }

  const int frames_;
  int next_ = 0;  // the capture thread's own
  std::mutex mutex_;
  std::condition_variable changed_;
  int delivered_ = 0;
  bool ended_ = false;
};

// The fake tracker, which also says how many frames it has tracked and can be made to wait.
class CountingTracker : public test::FakeTracker {
 public:
  std::function<void(int)> before = [](int) {};  // with the frame's capture index

  slam::FrameReport Track(const slam::FrameInput& input) override {
    before(IndexOf(input.timestamp));
    slam::FrameReport report = FakeTracker::Track(input);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++tracked_;
    }
    changed_.notify_all();
    return report;
  }
  void WaitTracked(int count) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return tracked_ >= count; });
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  int tracked_ = 0;
};

RunOptions LiveOptions(size_t capacity) {
  RunOptions options;
  options.progress = false;
  options.queue_capacity = capacity;
  options.colour = io::ColourMode::kColour;
  options.image_size = cv::Size(test::kCols, test::kRows);
  return options;
}

const io::Sequence& NoSequence() {
  static const io::Sequence sequence = [] {
    io::Sequence s;
    s.name = "fake";
    s.root = "fake0";
    s.sensor = io::SensorType::kRgbD;
    return s;
  }();
  return sequence;
}

TEST(LiveRunTest, SourceSlowerThanTrackingHasEveryFrameTracked) {
  FakeSource source(30);
  CountingTracker tracker;
  // Frame i is delivered only once frame i-1 is tracked: the source is slower by construction.
  source.before_grab = [&tracker](int i) { tracker.WaitTracked(i); };
  const auto masks = MakeMaskSource({}, NoSequence());
  const RunResult result = RunLive(source, tracker, *masks, LiveOptions(2));
  EXPECT_EQ(result.end, RunEnd::kCompleted) << result.end_message;
  EXPECT_TRUE(tracker.finished);
  ASSERT_EQ(result.frames.size(), 30u);
  ASSERT_TRUE(result.live.has_value());
  EXPECT_EQ(result.live->captured, 30u);
  EXPECT_EQ(result.live->dropped, 0u);
  for (int i = 0; i < 30; ++i) {
    EXPECT_EQ(result.frames[i].index, i);
    EXPECT_DOUBLE_EQ(result.frames[i].timestamp, StampOf(i));
  }
  EXPECT_TRUE(tracker.had_depth[0]);
  EXPECT_EQ(tracker.images[0].channels(), 3);
  EXPECT_EQ(result.camera.size(), 30u);
}

// --segment-every on a live source: the mask source runs on every K-th captured frame, counted
// from the first, as on recorded data; auto (0) segments at least the first frame.
TEST(LiveRunTest, SegmentEveryCountsCapturedFrames) {
  for (const int every : {3, 0}) {
    SCOPED_TRACE(every);
    FakeSource source(12);
    CountingTracker tracker;
    source.before_grab = [&tracker](int i) { tracker.WaitTracked(i); };
    const auto masks = MakeMaskSource({}, NoSequence());
    RunOptions options = LiveOptions(2);
    options.segment_every = every;
    const RunResult result = RunLive(source, tracker, *masks, options);
    EXPECT_EQ(result.end, RunEnd::kCompleted) << result.end_message;
    ASSERT_EQ(result.frames.size(), 12u);
    EXPECT_TRUE(result.frames[0].segmented);
    if (every == 3) {
      for (const FrameRecord& frame : result.frames) {
        EXPECT_EQ(frame.segmented, frame.index % 3 == 0) << "frame " << frame.index;
      }
    }
  }
}

TEST(LiveRunTest, SourceFasterThanTrackingDropsFramesAndCountsThem) {
  constexpr int kFrames = 40;
  FakeSource source(kFrames);
  CountingTracker tracker;
  // Tracking frame i takes until the source has delivered 10 more (or ended): more than the
  // queues between them hold, so frames must be dropped.
  tracker.before = [&source](int i) { source.WaitDelivered(i + 10); };
  const auto masks = MakeMaskSource({}, NoSequence());
  const RunResult result = RunLive(source, tracker, *masks, LiveOptions(2));
  EXPECT_EQ(result.end, RunEnd::kCompleted) << result.end_message;
  EXPECT_TRUE(tracker.finished);
  ASSERT_TRUE(result.live.has_value());
  EXPECT_EQ(result.live->captured, static_cast<size_t>(kFrames));
  EXPECT_GT(result.live->dropped, 0u);
  // Every frame was either tracked or dropped; the queue never held more than its bound.
  EXPECT_EQ(result.frames.size() + result.live->dropped, static_cast<size_t>(kFrames));
  EXPECT_LE(result.live->max_queued, 2u);
  // In capture order, and the oldest waiting frame is the one dropped: the last is tracked.
  for (size_t k = 1; k < result.frames.size(); ++k) {
    EXPECT_GT(result.frames[k].index, result.frames[k - 1].index);
  }
  EXPECT_EQ(result.frames.back().index, kFrames - 1);

  const moslam::testing::TempDir out;
  RunDescription description;
  description.dataset_path = "fake0";
  description.format_name = "camera";
  description.sensor = io::SensorType::kRgbD;
  WriteRunOutputs(NoSequence(), result, description, out.path());
  std::ifstream in(out.path() + "/summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["dropped"].get<size_t>(), result.live->dropped);
  EXPECT_EQ(summary["live"]["captured"].get<int>(), kFrames);
  EXPECT_EQ(summary["frames"].get<size_t>(), result.frames.size());
  EXPECT_EQ(summary["end"]["status"], "completed");
}

TEST(LiveRunTest, StopFlagEndsAnEndlessSourceCleanly) {
  FakeSource source(-1);
  CountingTracker tracker;
  std::atomic<int> stop{0};
  // The tracker raises the flag at its 5th frame, as SIGINT's handler would; the source waits
  // for each frame to be tracked, so the capture thread sees the flag at its next grab.
  tracker.before = [&stop](int i) {
    if (i == 4) stop = 2;
  };
  source.before_grab = [&tracker](int i) { tracker.WaitTracked(i); };
  RunOptions options = LiveOptions(2);
  options.stop = &stop;
  const auto masks = MakeMaskSource({}, NoSequence());
  const RunResult result = RunLive(source, tracker, *masks, options);
  EXPECT_EQ(result.end, RunEnd::kInterrupted) << result.end_message;
  EXPECT_TRUE(tracker.finished);
  EXPECT_EQ(result.frames.size(), 5u);
  EXPECT_EQ(result.camera.size(), 5u);
  EXPECT_EQ(result.live->dropped, 0u);
}

TEST(LiveRunTest, FailingDeviceEndsTheRunWithTheFramesBefore) {
  FakeSource source(-1);
  source.fail_at = 5;
  CountingTracker tracker;
  source.before_grab = [&tracker](int i) { tracker.WaitTracked(i); };
  const auto masks = MakeMaskSource({}, NoSequence());
  const RunResult result = RunLive(source, tracker, *masks, LiveOptions(2));
  EXPECT_EQ(result.end, RunEnd::kFailed);
  EXPECT_THAT(result.end_message, HasSubstr("fake0: delivered no frame"));
  EXPECT_TRUE(tracker.finished);
  EXPECT_EQ(result.frames.size(), 5u);
  EXPECT_THAT(ErrorOf([&] { RethrowFailure(result); }), HasSubstr("fake0"));
}

TEST(LiveRunTest, FrameOfAnotherSizeThanTheSettingsFailsNamingTheSource) {
  FakeSource source(3);
  source.size = cv::Size(test::kCols * 2, test::kRows);
  CountingTracker tracker;
  const auto masks = MakeMaskSource({}, NoSequence());
  const RunResult result = RunLive(source, tracker, *masks, LiveOptions(2));
  EXPECT_EQ(result.end, RunEnd::kFailed);
  EXPECT_THAT(result.end_message, HasSubstr("fake0: frame 0: the image is 48x16"));
  EXPECT_TRUE(result.frames.empty());
}

TEST(LiveRunTest, RecordedDataOptionsAreRefused) {
  FakeSource source(3);
  CountingTracker tracker;
  const auto masks = MakeMaskSource({}, NoSequence());
  RunOptions options = LiveOptions(2);
  options.realtime = true;
  EXPECT_THAT(ErrorOf([&] { RunLive(source, tracker, *masks, options); }),
              HasSubstr("fake0: --frames, --skip-frames and --realtime"));
  EXPECT_FALSE(tracker.finished);
}

}  // namespace
}  // namespace moslam::runner
