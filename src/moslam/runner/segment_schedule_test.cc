#include "moslam/runner/segment_schedule.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "moslam/util/error.h"

namespace moslam::runner {
namespace {

std::vector<size_t> DueFrames(SegmentSchedule& schedule, size_t frames) {
  std::vector<size_t> due;
  for (size_t i = 0; i < frames; ++i) {
    if (schedule.Due(i)) due.push_back(i);
  }
  return due;
}

TEST(SegmentSchedule, FixedEveryKthFrameFromTheFirst) {
  SegmentScheduleOptions options;
  options.every = 3;
  SegmentSchedule schedule(options);
  // Measurements change nothing for a fixed K.
  schedule.AddSegmentationMs(0, 100.0);
  schedule.AddTrackingMs(1.0);
  EXPECT_EQ(DueFrames(schedule, 10), (std::vector<size_t>{0, 3, 6, 9}));
  EXPECT_EQ(schedule.every(), 3);
  EXPECT_EQ(schedule.segmented(), 4);
}

TEST(SegmentSchedule, AutoSegmentsEveryFrameUntilBothTimesAreMeasured) {
  SegmentScheduleOptions options;
  options.every = 0;
  SegmentSchedule schedule(options);
  EXPECT_EQ(DueFrames(schedule, 3).size(), 3u);
  schedule.AddSegmentationMs(0, 60.0);  // no tracking time yet
  EXPECT_EQ(schedule.every(), 1);
  schedule.AddTrackingMs(20.0);
  EXPECT_EQ(schedule.every(), 3);  // ceil(60 / 20)
}

TEST(SegmentSchedule, AutoKeepsUpWithTheSlowerStageOfAPipelinedSource) {
  SegmentScheduleOptions options;
  options.every = 0;
  options.smoothing = 1.0;  // the last measurement only
  SegmentSchedule schedule(options);
  schedule.AddTrackingMs(20.0);
  schedule.AddSegmentationMs(0, 30.0);  // network
  schedule.AddSegmentationMs(1, 15.0);  // CRF, beside the network on another frame
  EXPECT_EQ(schedule.every(), 2);       // ceil(30 / 20), not ceil(45 / 20)
  // Offsets are frames since the range's first: due at 0, then 2 frames on.
  EXPECT_EQ(DueFrames(schedule, 7), (std::vector<size_t>{0, 2, 4, 6}));
  // A faster network: every frame again.
  schedule.AddSegmentationMs(0, 10.0);
  EXPECT_EQ(schedule.every(), 1);
  // A network far slower than tracking: capped.
  schedule.AddSegmentationMs(0, 1000.0);
  EXPECT_EQ(schedule.every(), options.max_every);
}

TEST(SegmentSchedule, AutoWithPacedFramesNeedsOnlyTheFrameInterval) {
  SegmentScheduleOptions options;
  options.every = 0;
  options.smoothing = 1.0;
  options.paced_interval_ms = 33.3;  // 30 Hz, --realtime
  SegmentSchedule schedule(options);
  schedule.AddTrackingMs(10.0);
  schedule.AddSegmentationMs(0, 30.0);
  EXPECT_EQ(schedule.every(), 1);  // the network fits the frame interval
  schedule.AddSegmentationMs(0, 50.0);
  EXPECT_EQ(schedule.every(), 2);
}

TEST(SegmentSchedule, MovingAveragesDampASingleSlowFrame) {
  SegmentScheduleOptions options;
  options.every = 0;
  options.smoothing = 0.2;
  SegmentSchedule schedule(options);
  schedule.AddTrackingMs(20.0);
  for (int i = 0; i < 10; ++i) schedule.AddSegmentationMs(0, 18.0);
  EXPECT_EQ(schedule.every(), 1);
  schedule.AddSegmentationMs(0, 200.0);  // one stall: average 0.8 * 18 + 0.2 * 200 = 54.4
  EXPECT_EQ(schedule.every(), 3);
  // It fades: 18 + 36.4 * 0.8^n ms after n ordinary frames, under 20 ms from n = 14 on.
  for (int i = 0; i < 13; ++i) schedule.AddSegmentationMs(0, 18.0);
  EXPECT_EQ(schedule.every(), 2);
  schedule.AddSegmentationMs(0, 18.0);
  EXPECT_EQ(schedule.every(), 1);
  // Negative or NaN times (a clock that failed) are ignored.
  schedule.AddSegmentationMs(0, -5.0);
  schedule.AddTrackingMs(std::nan(""));
  EXPECT_EQ(schedule.every(), 1);
}

TEST(SegmentSchedule, OptionsAreChecked) {
  SegmentScheduleOptions options;
  options.every = -1;
  EXPECT_THROW(options.Check(), InputError);
  options = {};
  options.max_every = 0;
  EXPECT_THROW(options.Check(), InputError);
  options = {};
  options.smoothing = 0.0;
  EXPECT_THROW(options.Check(), InputError);
  options = {};
  options.paced_interval_ms = -1.0;
  EXPECT_THROW(SegmentSchedule{options}, InputError);
}

}  // namespace
}  // namespace moslam::runner
