#include "moslam/runner/segmentation_stage.h"

namespace moslam::runner {

SegmentationStage::SegmentationStage(Upstream upstream, StopUpstream stop_upstream, Segment segment,
                                     size_t queue_capacity)
    : upstream_(std::move(upstream)),
      stop_upstream_(std::move(stop_upstream)),
      segment_(std::move(segment)),
      queue_(queue_capacity) {
  thread_ = std::thread([this] { Run(); });
}

SegmentationStage::~SegmentationStage() { Stop(); }

void SegmentationStage::Stop() {
  queue_.Close();    // wakes the stage if it waits for room
  stop_upstream_();  // wakes it if it waits for a frame
  if (thread_.joinable()) thread_.join();
}

void SegmentationStage::Run() {
  try {
    while (std::optional<LoadedFrame> frame = upstream_()) {
      if (queue_.closed()) return;  // stopped: do not segment a frame nobody will take
      segment_(*frame);
      if (!queue_.Push(std::move(*frame))) return;  // stopped by the consumer
    }
  } catch (...) {
    {
      std::lock_guard<std::mutex> lock(error_mutex_);
      error_ = std::current_exception();
    }
    stop_upstream_();  // the loader need not read frames nobody will track
  }
  queue_.Close();
}

std::optional<LoadedFrame> SegmentationStage::Next() {
  std::optional<LoadedFrame> frame = queue_.Pop();
  if (frame) return frame;
  std::lock_guard<std::mutex> lock(error_mutex_);
  if (error_) std::rethrow_exception(error_);
  return std::nullopt;
}

}  // namespace moslam::runner
