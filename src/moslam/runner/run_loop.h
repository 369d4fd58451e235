// The loop of `moslam run` as a library function: frames of a sequence, loaded ahead in their own
// thread (frame_loader.h) and given their movable-object masks in another (segmentation_stage.h),
// go through a Tracker one at a time; each frame's report and timings
// are recorded; at the end the tracker is finished and its trajectories collected. Writing the
// outputs is outputs.h's job.
#pragma once

#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "moslam/eval/trajectory.h"
#include "moslam/io/image.h"
#include "moslam/io/live_source.h"
#include "moslam/io/sequence.h"
#include "moslam/runner/frame_loader.h"
#include "moslam/runner/keyframe_graph.h"
#include "moslam/runner/live_capture.h"
#include "moslam/runner/mask_source.h"
#include "moslam/runner/tracker.h"

namespace moslam::runner {

// A half-open range of frame indices [first, last).
struct FrameRange {
  size_t first = 0;
  std::optional<size_t> last;  // nullopt: to the end of the sequence
};
// "A:B" (frames A..B-1), "A:" (from A), ":B" (up to B-1), as Python slices without negatives.
// InputError (naming `option`) for anything else.
FrameRange ParseFrameRange(const std::string& text, const std::string& option = "--frames");

struct FrameRecord;

// Watches the run from the tracking thread (the live viewer, viewer/live_viewer.h): called after
// each tracked frame with its record, the input the tracker got (images and mask) and the
// tracker, whose View() it may ask for. It must hand over and return quickly: it runs between
// frames, on tracking's time. It may block while its user paused the run: that is the pause.
class FrameObserver {
 public:
  virtual ~FrameObserver() = default;
  virtual void OnFrame(const FrameRecord& record, const slam::FrameInput& input,
                       Tracker& tracker) = 0;
};

struct RunOptions {
  FrameRange frames;  // sub-range to run; checked against the sequence in RunSequence
  // Frames (indices) inside `frames` that are not given to the tracker at all, as if the camera
  // had recorded nothing then (a gap: `moslam run --skip-frames A:B`); nullopt: none.
  std::optional<FrameRange> skip;
  bool realtime = false;      // pace frames by their timestamps instead of running flat out
  bool progress = true;       // periodic progress line (frames/s, ETA) via util/progress.h
  size_t queue_capacity = 4;  // frames loaded ahead of segmentation, and segmented ahead of
                              // tracking (> 0; each of the two queues holds this many)
  io::ColourMode colour = io::ColourMode::kGrey;  // how the left image is loaded
  double depth_factor = io::kTumDepthFactor;      // raw depth units per metre (RGB-D)
  // The mask source runs on every k-th frame of the range only (from its first frame); the
  // others reach the tracker without a mask, which carries the last one into them
  // (slam::SystemOptions::mask_propagation_frames; `moslam run --segment-every K`). 0: auto, k
  // chosen from the measured times as the run goes (runner/segment_schedule.h).
  int segment_every = 1;
  // The size every image must have: the settings' Camera.width x Camera.height, for which their
  // intrinsics hold (an image of another size would be tracked with wrong ones); 0x0: any size.
  // `image_size_source` names where it comes from (the settings file) in the error.
  cv::Size image_size;
  std::string image_size_source = "the settings";
  // Read between frames; once it is nonzero the run ends after the frame in hand as if the data
  // had ended there (the tracker is finished, the result holds every frame tracked) and the result
  // says RunEnd::kInterrupted. `moslam run` points it at the number of the signal (SIGINT,
  // SIGTERM) its handler stored. nullptr: never.
  const std::atomic<int>* stop = nullptr;
  // How a frame's images are read, in the loader thread; empty: from their files
  // (io::LoadFrameImages with `colour` and `depth_factor`). A video (`moslam run --dataset video`)
  // decodes its frames here (io::VideoReader). Throws InputError naming the file and frame.
  std::function<io::FrameImages(const io::FrameEntry&)> read_images;
  // When set, each keyframe's movable mask (slam::FrameReport::keyframe_mask, which the tracker
  // reports with SystemOptions::report_keyframe_masks) is written there as <stamp>.png (the stamp
  // with 6 decimals, as KeyFrameTrajectory.txt prints it; 255 = movable) as the run goes, and not
  // kept in the records. A keyframe without a mask gets no file. The folder must exist.
  std::string keyframe_mask_folder;
  FrameObserver* observer = nullptr;  // nullptr: nobody watches (FrameObserver)
  void Check() const;                 // InputError naming the field
};

// How a run ended.
enum class RunEnd {
  kCompleted,    // every frame of the range went through the tracker
  kFailed,       // an error while loading, segmenting or tracking a frame (RunResult::error)
  kInterrupted,  // RunOptions::stop was set
};
const char* RunEndName(RunEnd end);  // "completed", "failed", "interrupted"

// One frame as frames.csv records it.
struct FrameRecord {
  int index = 0;
  double timestamp = 0.0;
  slam::FrameReport report;
  double mask_ms = 0.0;     // the whole mask: reading, or network + CRF + post-processing
  double network_ms = 0.0;  // of mask_ms: the network
  double crf_ms = 0.0;      // of mask_ms: the CRF
  double mask_fraction = 0.0;
  bool segmented = true;  // the mask source ran on this frame (RunOptions::segment_every)
  double rss_mb = 0.0;    // the process's resident memory after this frame (MiB; 0: unknown)
};

struct RunResult {
  size_t first = 0;  // the range that was run
  size_t last = 0;
  size_t skipped = 0;  // frames of the range left out (RunOptions::skip)
  std::vector<FrameRecord> frames;
  eval::Trajectory camera;     // Tracker::CameraTrajectory after Finish
  eval::Trajectory keyframes;  // Tracker::KeyFrameTrajectory after Finish
  // Their graph (keyframe_graph.json); nullopt for a tracker that shows none.
  std::optional<KeyFrameGraph> graph;
  slam::MapSummary map;
  double wall_s = 0.0;  // from the start of loading to the end of Finish
  RunEnd end = RunEnd::kCompleted;
  std::string end_message;   // kFailed: the error's message; kInterrupted: the stop's value
  std::exception_ptr error;  // kFailed: the exception, to rethrow once the outputs are written
  // A live run (RunLive): frames captured and dropped; `first`..`last` is then 0..captured, and
  // a frame's index is its place in capture order, so the gaps in frames.csv are the drops.
  std::optional<LiveCounts> live;
};

// Rethrows the exception that ended a failed run; does nothing for any other end.
void RethrowFailure(const RunResult& result);

// The images of one frame per `options` (the loader thread's part).
LoadedFrame LoadImages(const io::FrameEntry& frame, const RunOptions& options);
// Sets frame->input.mask and the mask timings from `masks` (the segmentation thread's part).
void SegmentFrame(MaskSource& masks, LoadedFrame* frame);
// The same in two steps for a pipelined source (MaskSource::Pipelined): the network's thread
// runs PredictFrame (frame->pending_mask), the refinement thread RefineFrame (the mask); the
// times add up as SegmentFrame's.
void PredictFrame(MaskSource& masks, LoadedFrame* frame);
void RefineFrame(MaskSource& masks, LoadedFrame* frame);
// Both, in the caller's thread.
LoadedFrame LoadFrame(const io::FrameEntry& frame, MaskSource& masks, const RunOptions& options);

// Runs sequence.frames[range] through `tracker`. Options outside their range throw InputError
// before anything runs. An error in the middle of the run (loading, a mask source or the tracker
// throwing: an InputError naming the file, a network's error) ends it as a result, not an
// exception (issue 31): the loader and segmentation threads are stopped, the tracker is finished,
// and the result holds the frames tracked before the error with RunEnd::kFailed and the
// exception, so that the caller writes what was done and then fails (RethrowFailure).
RunResult RunSequence(const io::Sequence& sequence, Tracker& tracker, MaskSource& masks,
                      const RunOptions& options);

// Runs the frames of a live source through `tracker` as they arrive (live_capture.h): frames that
// come while tracking (or segmentation) is busy and the queue (RunOptions::queue_capacity) is
// full are dropped, the oldest first, and counted (RunResult::live, the log). Ends when the
// source ends, on RunOptions::stop (RunEnd::kInterrupted; the frames still queued are not
// tracked) or on an error (RunEnd::kFailed, as RunSequence). RunOptions::frames, skip and
// realtime are for recorded data: InputError. RunOptions::read_images is not used.
RunResult RunLive(io::LiveSource& source, Tracker& tracker, MaskSource& masks,
                  const RunOptions& options);

}  // namespace moslam::runner
