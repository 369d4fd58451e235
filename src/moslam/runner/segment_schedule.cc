#include "moslam/runner/segment_schedule.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "moslam/util/error.h"

namespace moslam::runner {

void SegmentScheduleOptions::Check() const {
  if (every < 0) {
    throw InputError(fmt::format("--segment-every: must be >= 1 or auto, got {}", every));
  }
  if (max_every < 1) {
    throw InputError(
        fmt::format("SegmentScheduleOptions.max_every: must be >= 1, got {}", max_every));
  }
  if (!(paced_interval_ms >= 0.0)) {
    throw InputError(fmt::format("SegmentScheduleOptions.paced_interval_ms: must be >= 0, got {}",
                                 paced_interval_ms));
  }
  if (!(smoothing > 0.0 && smoothing <= 1.0)) {
    throw InputError(
        fmt::format("SegmentScheduleOptions.smoothing: must be in (0, 1], got {}", smoothing));
  }
}

SegmentSchedule::SegmentSchedule(const SegmentScheduleOptions& options)
    : options_((options.Check(), options)) {}

namespace {
// An exponential moving average; `count` measurements so far. Negative or NaN times (a clock
// that failed) are ignored.
void Average(double ms, double weight, double* average, long* count) {
  if (!(ms >= 0.0)) return;
  *average = *count > 0 ? (1.0 - weight) * *average + weight * ms : ms;
  ++*count;
}
}  // namespace

void SegmentSchedule::AddSegmentationMs(int stage, double ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  const int i = stage == 0 ? 0 : 1;
  Average(ms, options_.smoothing, &stage_ms_[i], &stage_count_[i]);
}

void SegmentSchedule::AddTrackingMs(double ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  Average(ms, options_.smoothing, &tracking_ms_, &tracking_count_);
}

int SegmentSchedule::EveryLocked() const {
  if (options_.every > 0) return options_.every;
  if (stage_count_[0] + stage_count_[1] == 0 || tracking_count_ == 0) return 1;
  const double segmentation = std::max(stage_ms_[0], stage_ms_[1]);
  const double budget = std::max(tracking_ms_, options_.paced_interval_ms);
  if (segmentation <= budget) return 1;
  if (budget <= 0.0) return options_.max_every;
  const double every = std::ceil(segmentation / budget);
  return every >= options_.max_every ? options_.max_every : static_cast<int>(every);
}

bool SegmentSchedule::Due(size_t offset) {
  std::lock_guard<std::mutex> lock(mutex_);
  bool due;
  if (options_.every > 0) {
    due = offset % static_cast<size_t>(options_.every) == 0;
  } else {
    due = !any_due_ || offset >= last_due_ + static_cast<size_t>(EveryLocked());
  }
  if (due) {
    any_due_ = true;
    last_due_ = offset;
    ++segmented_;
  }
  return due;
}

int SegmentSchedule::every() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return EveryLocked();
}

long SegmentSchedule::segmented() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return segmented_;
}

}  // namespace moslam::runner
