// A recorded sequence played as a live source: frames in order with their own stamps, each read
// by the given function, then the end; paced by the stamps (a 20 ms sequence takes >= 20 ms).
#include "moslam/io/live_source.h"

#include <chrono>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/error_of.h"

namespace moslam::io {
namespace {

TEST(ReplaySource, DeliversEveryFrameAtItsStamp) {
  Sequence sequence;
  sequence.root = "recorded";
  sequence.sensor = SensorType::kRgbD;
  for (int i = 0; i < 3; ++i) sequence.frames.push_back({i, 5.0 + 0.01 * i, "rgb", "", "depth"});
  std::vector<int> loaded;
  ReplaySource source(sequence, [&loaded](const FrameEntry& frame) {
    loaded.push_back(frame.index);
    FrameImages images;
    images.left = cv::Mat(2, 2, CV_8UC1, cv::Scalar(frame.index));
    return images;
  });
  EXPECT_EQ(source.name(), "recorded");
  EXPECT_EQ(source.sensor(), SensorType::kRgbD);
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 3; ++i) {
    const std::optional<LiveFrame> frame = source.Grab();
    ASSERT_TRUE(frame.has_value());
    EXPECT_DOUBLE_EQ(frame->timestamp, 5.0 + 0.01 * i);
    EXPECT_EQ(frame->images.left.at<uint8_t>(0, 0), i);
  }
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(20));
  EXPECT_FALSE(source.Grab().has_value());
  EXPECT_EQ(loaded, (std::vector<int>{0, 1, 2}));
  EXPECT_THAT(moslam::testing::ErrorOf([&] { ReplaySource(sequence, nullptr, 0.0); }),
              ::testing::HasSubstr("speed"));
}

TEST(LiveClock, NeverGoesBack) {
  const LiveClock clock;
  const double a = clock.Now();
  EXPECT_GT(a, 1.7e9);  // Unix seconds
  EXPECT_GT(clock.NextAfter(a + 10.0), a + 10.0);
}

}  // namespace
}  // namespace moslam::io
