// The segmentation stage of `moslam run`: a thread between image loading and tracking that
// computes each frame's movable-object mask, so that frame k+1 is segmented while frame k is
// tracked. Frames stay in order and each carries its own mask: tracking never uses a mask of
// another frame.
//
//   loader thread --BoundedQueue--> segmentation thread --BoundedQueue--> tracking (caller)
//
// Stop rules (the same as FrameLoader's): when the upstream ends, the stage closes its queue and
// Next() returns nullopt once the queue is drained. When segmenting (or the upstream) throws, the
// stage keeps the exception, stops the upstream, closes its queue, and Next() rethrows it after
// the frames finished before it. Stop() (also run by the destructor, e.g. when tracking threw)
// closes the queue, which wakes a stage blocked on a full queue, stops the upstream, which wakes
// a stage waiting for a frame, and joins the thread: no deadlock, no leaked thread.
#pragma once

#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "moslam/runner/frame_loader.h"
#include "moslam/util/bounded_queue.h"

namespace moslam::runner {

class SegmentationStage {
 public:
  // The next frame from upstream, nullopt at its end (e.g. FrameLoader::Next); may throw.
  using Upstream = std::function<std::optional<LoadedFrame>()>;
  // Ends the upstream early, so that a pending Upstream call returns (e.g. FrameLoader::Stop).
  using StopUpstream = std::function<void()>;
  // Computes the frame's mask in place (LoadedFrame::input.mask and the mask timings); may throw.
  using Segment = std::function<void(LoadedFrame&)>;

  // Starts the thread at once. queue_capacity: segmented frames held for tracking (> 0).
  SegmentationStage(Upstream upstream, StopUpstream stop_upstream, Segment segment,
                    size_t queue_capacity);
  ~SegmentationStage();
  SegmentationStage(const SegmentationStage&) = delete;
  SegmentationStage& operator=(const SegmentationStage&) = delete;

  // The next segmented frame; nullopt at the end. Rethrows the stage's exception once reached.
  std::optional<LoadedFrame> Next();
  // Explicit stop: no more frames; joins the thread. Idempotent.
  void Stop();

 private:
  void Run();

  Upstream upstream_;
  StopUpstream stop_upstream_;
  Segment segment_;
  BoundedQueue<LoadedFrame> queue_;
  std::mutex error_mutex_;
  std::exception_ptr error_;
  std::thread thread_;  // last member: started after everything it uses exists
};

}  // namespace moslam::runner
