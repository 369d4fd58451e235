// The capture thread of a live run (`moslam run --dataset camera|kinect`): it takes every frame a
// io::LiveSource delivers, as a camera delivers them whether or not anyone is ready, and hands
// them to the segmentation stage and tracking through a BoundedQueue. When the queue is full
// (tracking, or segmentation, is busy) the oldest waiting frame is dropped and counted, so the
// tracker always gets the freshest frames and memory stays bounded: a live run never queues
// without bound and never falls behind the camera by more than the queue.
//
//   source.Grab() --capture thread--> BoundedQueue (drop oldest) --> segmentation --> tracking
//
// Stop rules, as FrameLoader's: when the source ends (Grab() returns nullopt) the thread closes
// the queue and Next() returns nullopt once it is drained; when Grab() or the conversion throws
// (an unplugged camera), the exception is kept, the queue closed, and Next() rethrows it after
// the frames before it. The stop flag (RunOptions::stop, set by SIGINT) is read after each grab:
// a signal handler cannot wake a thread, and a live source returns within a frame interval.
// Stop() (and the destructor) closes the queue; the destructor joins the thread after its
// current Grab() returns.
#pragma once

#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "moslam/io/live_source.h"
#include "moslam/runner/frame_loader.h"
#include "moslam/util/bounded_queue.h"

namespace moslam::runner {

struct LiveCaptureOptions {
  size_t queue_capacity = 2;  // frames waiting for segmentation/tracking (> 0); more are dropped
  io::ColourMode colour = io::ColourMode::kGrey;  // how the left image reaches the tracker
  // The size the settings' intrinsics are for (0x0: any): a frame of another size is an error.
  cv::Size image_size;
  const std::atomic<int>* stop = nullptr;  // nonzero: stop after the frame in hand
  void Check() const;                      // InputError naming the field
};

// Counts of a live run; captured == tracked + dropped once a run that was not stopped drains.
struct LiveCounts {
  size_t captured = 0;    // frames Grab() delivered
  size_t dropped = 0;     // frames dropped because the queue was full
  size_t max_queued = 0;  // the most frames the queue held at once (<= queue_capacity)
};

class LiveCapture {
 public:
  // Starts the thread at once. `source` must outlive the capture.
  LiveCapture(io::LiveSource& source, const LiveCaptureOptions& options);
  ~LiveCapture();
  LiveCapture(const LiveCapture&) = delete;
  LiveCapture& operator=(const LiveCapture&) = delete;

  // The next frame, numbered by capture order (gaps are dropped frames); nullopt at the end.
  // Rethrows the capture thread's exception once it is reached.
  std::optional<LoadedFrame> Next();
  void Stop() { queue_.Close(); }
  LiveCounts counts() const;
  // Whether the capture ended because the stop flag was set (not because the source ended).
  bool stopped_by_flag() const { return stopped_by_flag_.load(); }

 private:
  void Run();
  LoadedFrame Convert(io::LiveFrame frame, size_t index) const;
  void Hand(LoadedFrame frame);

  io::LiveSource& source_;
  const LiveCaptureOptions options_;
  BoundedQueue<LoadedFrame> queue_;
  mutable std::mutex mutex_;  // guards counts_ and error_
  LiveCounts counts_;
  std::exception_ptr error_;
  std::atomic<bool> stopped_by_flag_{false};
  std::thread thread_;  // last member: started after everything it uses exists
};

}  // namespace moslam::runner
