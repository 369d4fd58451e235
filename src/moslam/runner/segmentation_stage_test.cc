// The segmentation stage between image loading and tracking: order, each frame with its own
// mask, overlap of segmentation and tracking, clean stops at the end of a sequence, on a provider
// failure and on an early stop by the consumer. No timing thresholds: overlap is shown by events.
#include "moslam/runner/segmentation_stage.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/io/dataset.h"
#include "moslam/runner/model_mask_source.h"
#include "moslam/runner/run_loop.h"
#include "moslam/runner/test_sequences.h"
#include "moslam/semantic/dense_crf.h"
#include "moslam/testing/error_of.h"

namespace moslam::runner {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

io::Sequence FakeSequence(int frames) {
  io::Sequence sequence;
  for (int i = 0; i < frames; ++i) sequence.frames.push_back({i, 0.1 * i, "", "", ""});
  return sequence;
}

// A frame whose image is filled with its index (mod 256), without touching files.
LoadedFrame MakeFrame(const io::FrameEntry& entry) {
  LoadedFrame frame;
  frame.index = entry.index;
  frame.entry = &entry;
  frame.input.image = cv::Mat(4, 6, CV_8UC1, cv::Scalar(entry.index % 256));
  return frame;
}

// Marks the mask with the image's value: a frame carrying another frame's mask is detectable.
void MaskFromImage(LoadedFrame& frame) { frame.input.mask = frame.input.image.clone(); }

TEST(SegmentationStage, EndOfSequenceDrainsInOrderWithEachFrameItsOwnMask) {
  const io::Sequence sequence = FakeSequence(200);
  FrameLoader loader(sequence, 0, sequence.size(), MakeFrame, 1);
  SegmentationStage stage([&] { return loader.Next(); }, [&] { loader.Stop(); }, MaskFromImage, 1);
  int expected = 0;
  while (std::optional<LoadedFrame> frame = stage.Next()) {
    ASSERT_EQ(frame->index, expected);
    ASSERT_EQ(frame->input.mask.at<uint8_t>(0, 0), expected % 256);
    ++expected;
  }
  EXPECT_EQ(expected, 200);
  EXPECT_FALSE(stage.Next());  // stays at the end
}

TEST(SegmentationStage, ProviderFailureStopsTheRunWithItsErrorAfterEarlierFrames) {
  const io::Sequence sequence = FakeSequence(1000);
  FrameLoader loader(sequence, 0, sequence.size(), MakeFrame, 2);
  std::atomic<bool> upstream_stopped{false};
  SegmentationStage stage([&] { return loader.Next(); },
                          [&] {
                            upstream_stopped = true;
                            loader.Stop();
                          },
                          [](LoadedFrame& f) {
                            if (f.index == 3) throw std::runtime_error("network exploded");
                            MaskFromImage(f);
                          },
                          2);
  for (int i = 0; i < 3; ++i) {
    const std::optional<LoadedFrame> frame = stage.Next();
    ASSERT_TRUE(frame);
    EXPECT_EQ(frame->index, i);
  }
  EXPECT_THROW(
      {
        try {
          stage.Next();
        } catch (const std::runtime_error& e) {
          EXPECT_STREQ(e.what(), "network exploded");
          throw;
        }
      },
      std::runtime_error);
  EXPECT_TRUE(upstream_stopped);  // the loader was told to stop, not left to load 1000 frames
}

TEST(SegmentationStage, UpstreamFailureReachesTheConsumer) {
  const io::Sequence sequence = FakeSequence(10);
  FrameLoader loader(
      sequence, 0, sequence.size(),
      [](const io::FrameEntry& e) {
        if (e.index == 5) ThrowInput("image {} is missing", e.index);
        return MakeFrame(e);
      },
      4);
  SegmentationStage stage([&] { return loader.Next(); }, [&] { loader.Stop(); }, MaskFromImage, 4);
  int frames = 0;
  const std::string error = ErrorOf([&] {
    while (stage.Next()) ++frames;
  });
  EXPECT_EQ(frames, 5);
  EXPECT_THAT(error, HasSubstr("image 5 is missing"));
}

TEST(SegmentationStage, EarlyStopWithFullQueuesDoesNotDeadlock) {
  const io::Sequence sequence = FakeSequence(100000);
  FrameLoader loader(sequence, 0, sequence.size(), MakeFrame, 1);
  SegmentationStage stage([&] { return loader.Next(); }, [&] { loader.Stop(); }, MaskFromImage, 1);
  ASSERT_TRUE(stage.Next());
  stage.Stop();  // both threads are (or will be) blocked on full queues: Stop must free them
  stage.Stop();  // idempotent
  int left = 0;
  while (stage.Next()) ++left;  // at most what was queued before the stop
  EXPECT_LE(left, 1);
}

TEST(SegmentationStage, NextFrameIsSegmentedWhileTheCurrentOneIsTracked) {
  const io::Sequence sequence = FakeSequence(3);
  FrameLoader loader(sequence, 0, sequence.size(), MakeFrame, 4);
  std::mutex mutex;
  std::condition_variable segmented;
  int last_segmented = -1;
  SegmentationStage stage([&] { return loader.Next(); }, [&] { loader.Stop(); },
                          [&](LoadedFrame& f) {
                            MaskFromImage(f);
                            std::lock_guard<std::mutex> lock(mutex);
                            last_segmented = f.index;
                            segmented.notify_all();
                          },
                          4);
  const std::optional<LoadedFrame> first = stage.Next();
  ASSERT_TRUE(first);
  // "Tracking" frame 0 waits for the stage to finish frame 1 on its own: this can only happen
  // when segmentation runs concurrently. The bound only guards against a hang if it does not.
  std::unique_lock<std::mutex> lock(mutex);
  EXPECT_TRUE(
      segmented.wait_for(lock, std::chrono::minutes(1), [&] { return last_segmented >= 1; }));
}

// A mask source over a fake provider, pipelined: Predict() (the network's thread) gives
// probabilities, Refine() (the refinement thread) the mask; the network and CRF times reach the
// frame records. `fail_predict_at` / `fail_refine_at`: the call that throws (-1: none).
class FakeProvider : public semantic::MaskProvider {
 public:
  explicit FakeProvider(int fail_predict_at, int fail_refine_at = -1)
      : fail_predict_at_(fail_predict_at), fail_refine_at_(fail_refine_at) {}
  semantic::Prediction Predict(const semantic::MaskInput& input) override {
    if (predictions_++ == fail_predict_at_) ThrowInput("fake network: out of memory");
    // Movable where the image is brighter than 42 (TUM test frames are 40 + i).
    const int sizes[] = {2, input.image.rows, input.image.cols};
    semantic::Prediction prediction;
    prediction.probabilities = cv::Mat(3, sizes, CV_32F, cv::Scalar(0.0f));
    semantic::LabelPlane(prediction.probabilities, 1).setTo(1.0f, input.image > 42);
    semantic::LabelPlane(prediction.probabilities, 0).setTo(1.0f, input.image <= 42);
    prediction.network_ms = 7.0;
    return prediction;
  }
  semantic::MaskResult Refine(semantic::Prediction prediction,
                              const semantic::MaskInput& input) override {
    if (refinements_++ == fail_refine_at_) ThrowInput("fake CRF: bad depth");
    semantic::MaskResult result;
    result.mask = cv::Mat(input.image.size(), CV_8UC1, cv::Scalar(0));
    result.mask.setTo(255, semantic::LabelPlane(prediction.probabilities, 1) > 0.5f);
    result.network_ms = prediction.network_ms;
    result.crf_ms = 3.0;
    return result;
  }
  const std::vector<std::string>& class_names() const override { return names_; }
  const std::vector<bool>& movable() const override { return movable_; }
  std::string Describe() const override { return "fake"; }

 private:
  int fail_predict_at_;
  int fail_refine_at_;
  std::atomic<int> predictions_{0};
  std::atomic<int> refinements_{0};
  std::vector<std::string> names_ = {"static", "thing"};
  std::vector<bool> movable_ = {false, true};
};

RunOptions Quiet() {
  RunOptions options;
  options.progress = false;
  options.queue_capacity = 1;
  return options;
}

TEST(SegmentationStage, RunSequenceGivesEachFrameTheMaskOfItsOwnImage) {
  testing::TempDir data;
  test::MakeTum(data, 6);
  const io::Sequence seq = io::ReadDataset(data.path());
  test::FakeTracker tracker;
  const auto masks = MakeProviderMaskSource(std::make_unique<FakeProvider>(-1));
  const RunResult result = RunSequence(seq, tracker, *masks, Quiet());
  ASSERT_EQ(tracker.masks.size(), 6u);
  for (size_t i = 0; i < 6; ++i) {
    const bool movable = tracker.images[i].at<uint8_t>(0, 0) > 42;
    EXPECT_EQ(cv::countNonZero(tracker.masks[i]), movable ? test::kCols * test::kRows : 0) << i;
    EXPECT_EQ(result.frames[i].network_ms, 7.0);
    EXPECT_EQ(result.frames[i].crf_ms, 3.0);
    EXPECT_GE(result.frames[i].mask_ms, 0.0);
  }
  EXPECT_TRUE(tracker.finished);
}

TEST(SegmentationStage, RunSequenceStopsCleanlyWhenTheProviderFails) {
  testing::TempDir data;
  test::MakeTum(data, 40);
  const io::Sequence seq = io::ReadDataset(data.path());
  test::FakeTracker tracker;
  const auto masks = MakeProviderMaskSource(std::make_unique<FakeProvider>(2));
  EXPECT_THAT(ErrorOf([&] { RethrowFailure(RunSequence(seq, tracker, *masks, Quiet())); }),
              HasSubstr("out of memory"));
  EXPECT_EQ(tracker.masks.size(), 2u);  // frames 0 and 1 were tracked, nothing after the error
}

TEST(SegmentationStage, RunSequenceStopsCleanlyWhenTheRefinementFails) {
  testing::TempDir data;
  test::MakeTum(data, 40);
  const io::Sequence seq = io::ReadDataset(data.path());
  test::FakeTracker tracker;
  const auto masks = MakeProviderMaskSource(std::make_unique<FakeProvider>(-1, 3));
  EXPECT_THAT(ErrorOf([&] { RethrowFailure(RunSequence(seq, tracker, *masks, Quiet())); }),
              HasSubstr("bad depth"));
  EXPECT_EQ(tracker.masks.size(), 3u);  // frames 0 to 2 were tracked, nothing after the error
}

TEST(SegmentationStage, PipelinedStepsGiveWhatSegmentGives) {
  testing::TempDir data;
  test::MakeTum(data, 4);
  const io::Sequence seq = io::ReadDataset(data.path());
  const auto pipelined = MakeProviderMaskSource(std::make_unique<FakeProvider>(-1));
  FakeProvider whole(-1);
  ASSERT_TRUE(pipelined->Pipelined());
  for (const io::FrameEntry& entry : seq.frames) {
    LoadedFrame frame = LoadImages(entry, Quiet());
    PredictFrame(*pipelined, &frame);
    ASSERT_TRUE(frame.pending_mask.has_value());
    EXPECT_TRUE(frame.input.mask.empty());  // no mask before refinement
    EXPECT_EQ(frame.network_ms, 7.0);
    RefineFrame(*pipelined, &frame);
    EXPECT_FALSE(frame.pending_mask.has_value());
    const semantic::MaskResult expected = whole.Segment({frame.input.image, frame.input.depth});
    ASSERT_EQ(frame.input.mask.size(), expected.mask.size());
    EXPECT_EQ(cv::countNonZero(frame.input.mask != expected.mask), 0) << entry.index;
    EXPECT_EQ(frame.crf_ms, 3.0);
    EXPECT_DOUBLE_EQ(frame.mask_fraction, static_cast<double>(cv::countNonZero(expected.mask)) /
                                              static_cast<double>(expected.mask.total()));
  }
}

}  // namespace
}  // namespace moslam::runner
