// Which frames the mask source runs on (`moslam run --segment-every K|auto`, issue 28). The frames
// between get the masks carried from the segmented ones (slam/mask_propagation.h), so a network
// slower than tracking need not set the frame rate: NGD-SLAM (Zhang et al. 2024) runs its detector
// on a few frames and propagates between them.
//
// A fixed K segments the range's first frame and every K-th after it. `auto` picks K as the run
// goes, from what it measures: the smallest K at which the mask source keeps up with the tracker,
// K = ceil(segmentation ms / tracking ms), where segmentation ms is the slower of a pipelined
// source's two stages (network and CRF run beside each other on different frames) and tracking ms
// the tracker's own time per frame, or the data set's frame interval when frames are paced
// (--realtime) and that is longer. Both are exponential moving averages; until both have been
// measured every frame is segmented. Timing decides the frames, so `auto` cannot be repeated
// exactly and --deterministic refuses it.
#pragma once

#include <mutex>

namespace moslam::runner {

struct SegmentScheduleOptions {
  int every = 1;  // K >= 1; 0: auto
  // auto: the largest K it may choose (more frames between masks than this and the carried masks
  // lag the people by more than the propagation's few frames can follow).
  int max_every = 4;
  // auto: the frames' interval when they are paced (--realtime), ms; 0: frames as fast as the
  // tracker takes them.
  double paced_interval_ms = 0.0;
  // auto: weight of the newest measurement in the moving averages (0, 1].
  double smoothing = 0.2;
  void Check() const;  // InputError naming the field
};

// Thread-safe: Due() is called by the first segmentation stage, the measurements by every stage
// and the tracking loop.
class SegmentSchedule {
 public:
  explicit SegmentSchedule(const SegmentScheduleOptions& options);

  // Whether the source runs on the frame at `offset` from the range's first frame; called once
  // per frame, in order.
  bool Due(size_t offset);
  // A segmented frame's time in one stage of the source (`stage` 0: the network, or a source's
  // whole mask when it is not pipelined; 1: the CRF), ms.
  void AddSegmentationMs(int stage, double ms);
  // The tracker's time for one frame, ms.
  void AddTrackingMs(double ms);

  // The K in use now (auto: 1 until both times are measured).
  int every() const;
  // Frames segmented so far.
  long segmented() const;

 private:
  int EveryLocked() const;

  const SegmentScheduleOptions options_;
  mutable std::mutex mutex_;
  double stage_ms_[2] = {0.0, 0.0};  // moving averages
  long stage_count_[2] = {0, 0};     // measurements in them
  double tracking_ms_ = 0.0;
  long tracking_count_ = 0;
  size_t last_due_ = 0;
  bool any_due_ = false;
  long segmented_ = 0;
};

}  // namespace moslam::runner
