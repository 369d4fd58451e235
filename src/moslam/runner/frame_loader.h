// Image loading in its own thread, ahead of tracking: a producer reads frames (images, depth, the
// movable-object mask) into a BoundedQueue that the run loop pops from, so disk and PNG decoding
// overlap with tracking while the bound keeps memory flat.
//
// Stop rules: at the end of the range the loader closes the queue and Next() returns nullopt once
// the queue is drained. When loading throws (a missing image, a missing mask), the loader keeps
// the exception, closes the queue, and Next() rethrows it in the consumer's thread after the
// frames loaded before it. Destroying the FrameLoader early (the consumer threw) closes the queue,
// which wakes a loader blocked on a full queue, and joins it: no deadlock, no leaked thread.
#pragma once

#include <cstddef>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "moslam/io/sequence.h"
#include "moslam/runner/mask_source.h"
#include "moslam/slam/system.h"
#include "moslam/util/bounded_queue.h"

namespace moslam::runner {

struct LoadedFrame {
  int index = 0;                          // FrameEntry::index
  const io::FrameEntry* entry = nullptr;  // the sequence's entry (it outlives the run)
  // A live frame (live_capture.h) has no sequence to point into: it owns its entry, and `entry`
  // points at it (a shared_ptr, so that moving the frame keeps `entry` valid).
  std::shared_ptr<const io::FrameEntry> owned_entry;
  slam::FrameInput input;
  double load_ms = 0.0;        // reading and decoding the images
  double mask_ms = 0.0;        // computing or reading the mask (all of it)
  double network_ms = 0.0;     // of mask_ms: the network (pre-processing and inference)
  double crf_ms = 0.0;         // of mask_ms: the CRF
  double mask_fraction = 0.0;  // share of movable pixels, 0 when there is no mask
  // The mask source runs on this frame (RunOptions::segment_every; set by the first
  // segmentation stage).
  bool segment = true;
  // Between the two segmentation threads of a pipelined mask source: the network's output.
  std::optional<FrameMask> pending_mask;
};

// Loads one frame; throws InputError naming the file on failure. Called in the loader thread.
using LoadFunction = std::function<LoadedFrame(const io::FrameEntry&)>;

class FrameLoader {
 public:
  // Starts the thread at once; loads sequence.frames[first, last) in order.
  FrameLoader(const io::Sequence& sequence, size_t first, size_t last, LoadFunction load,
              size_t queue_capacity);
  ~FrameLoader();
  FrameLoader(const FrameLoader&) = delete;
  FrameLoader& operator=(const FrameLoader&) = delete;

  // The next frame; nullopt at the end. Rethrows the loader's exception once it is reached.
  std::optional<LoadedFrame> Next();
  // Explicit stop from the consumer's side: closes the queue (the loader stops at its next push,
  // a pending Next() returns the frames already loaded and then nullopt). The destructor joins.
  void Stop() { queue_.Close(); }

 private:
  void Run(const io::Sequence& sequence, size_t first, size_t last);

  LoadFunction load_;
  BoundedQueue<LoadedFrame> queue_;
  std::mutex error_mutex_;
  std::exception_ptr error_;
  std::thread thread_;  // last member: started after everything it uses exists
};

}  // namespace moslam::runner
