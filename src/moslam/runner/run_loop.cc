#include "moslam/runner/run_loop.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string_view>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "moslam/runner/live_capture.h"
#include "moslam/runner/segment_schedule.h"
#include "moslam/runner/segmentation_stage.h"
#include "moslam/util/atomic_file.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/util/process.h"
#include "moslam/util/progress.h"
#include "moslam/util/strings.h"

namespace moslam::runner {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Tracks one frame; an InputError from inside the tracker (an image it cannot use) is given
// the frame's index and image file, which the tracker does not know.
slam::FrameReport TrackFrame(Tracker& tracker, const LoadedFrame& frame) {
  try {
    return tracker.Track(frame.input);
  } catch (const InputError& e) {
    const std::string image = frame.entry != nullptr ? frame.entry->image_left : "?";
    ThrowInFile(image, fmt::format("frame {}: {}", frame.index, e.what()));
  }
}

}  // namespace

const char* StateName(slam::TrackingState state) {
  switch (state) {
    case slam::TrackingState::kNotInitialized:
      return "not_initialized";
    case slam::TrackingState::kOk:
      return "ok";
    case slam::TrackingState::kLost:
      return "lost";
  }
  return "?";
}

const char* RunEndName(RunEnd end) {
  switch (end) {
    case RunEnd::kCompleted:
      return "completed";
    case RunEnd::kFailed:
      return "failed";
    case RunEnd::kInterrupted:
      return "interrupted";
  }
  return "?";
}

void RethrowFailure(const RunResult& result) {
  if (result.end == RunEnd::kFailed && result.error) std::rethrow_exception(result.error);
}

FrameRange ParseFrameRange(const std::string& text, const std::string& option) {
  const size_t colon = text.find(':');
  if (colon == std::string::npos || text.find(':', colon + 1) != std::string::npos) {
    ThrowInput("{}: expected A:B, A: or :B (frame indices, B excluded), got '{}'", option, text);
  }
  auto parse = [&](std::string_view part) -> std::optional<size_t> {
    part = Trim(part);
    if (part.empty()) return std::nullopt;
    const auto value = ParseInt(part);
    if (!value || *value < 0) {
      ThrowInput("{}: '{}' is not a frame index (a whole number >= 0) in '{}'", option, part, text);
    }
    return static_cast<size_t>(*value);
  };
  FrameRange range;
  range.first = parse(std::string_view(text).substr(0, colon)).value_or(0);
  range.last = parse(std::string_view(text).substr(colon + 1));
  if (range.last && *range.last <= range.first) {
    ThrowInput("{}: the range '{}' is empty (B must be greater than A)", option, text);
  }
  return range;
}

void RunOptions::Check() const {
  if (queue_capacity == 0) ThrowInput("run.queue_capacity: must be > 0");
  if (!(depth_factor > 0.0)) ThrowInput("run.depth_factor: must be > 0, got {}", depth_factor);
  if (segment_every < 0) {
    ThrowInput("--segment-every: must be >= 1, or 0 for auto, got {}", segment_every);
  }
  if (image_size.width < 0 || image_size.height < 0) {
    ThrowInput("run.image_size: must not be negative, got {}x{}", image_size.width,
               image_size.height);
  }
  if (!keyframe_mask_folder.empty() && !std::filesystem::is_directory(keyframe_mask_folder)) {
    ThrowInput("run.keyframe_mask_folder: no folder {}", keyframe_mask_folder);
  }
}

LoadedFrame LoadImages(const io::FrameEntry& frame, const RunOptions& options) {
  LoadedFrame loaded;
  loaded.index = frame.index;
  loaded.entry = &frame;
  const auto start = Clock::now();
  io::FrameImages images = options.read_images
                               ? options.read_images(frame)
                               : io::LoadFrameImages(frame, options.colour, options.depth_factor);
  loaded.load_ms = MsSince(start);
  // LoadFrameImages makes the right and depth images agree with the left one.
  if (!options.image_size.empty() && images.left.size() != options.image_size) {
    ThrowInFile(
        frame.image_left,
        fmt::format("frame {}: the image is {}x{}, but Camera.width x Camera.height in {} are "
                    "{}x{}, the size its intrinsics are for",
                    frame.index, images.left.cols, images.left.rows, options.image_size_source,
                    options.image_size.width, options.image_size.height));
  }
  loaded.input.timestamp = frame.timestamp;
  loaded.input.image = std::move(images.left);
  loaded.input.right = std::move(images.right);
  loaded.input.depth = std::move(images.depth);
  return loaded;
}

void PredictFrame(MaskSource& masks, LoadedFrame* frame) {
  MOSLAM_CHECK(frame->entry != nullptr) << "a loaded frame without its sequence entry";
  const auto start = Clock::now();
  frame->pending_mask = masks.Predict(*frame->entry, frame->input.image, frame->input.depth);
  frame->mask_ms = MsSince(start);
  frame->network_ms = frame->pending_mask->network_ms;
}

void RefineFrame(MaskSource& masks, LoadedFrame* frame) {
  MOSLAM_CHECK(frame->pending_mask.has_value()) << "RefineFrame() before PredictFrame()";
  const auto start = Clock::now();
  FrameMask& mask = *frame->pending_mask;
  masks.Refine(&mask, frame->input.image, frame->input.depth);
  frame->mask_ms += MsSince(start);
  frame->network_ms = mask.network_ms;
  frame->crf_ms = mask.crf_ms;
  frame->mask_fraction = mask.fraction;
  frame->input.mask = std::move(mask.mask);
  frame->pending_mask.reset();
}

void SegmentFrame(MaskSource& masks, LoadedFrame* frame) {
  PredictFrame(masks, frame);
  RefineFrame(masks, frame);
}

LoadedFrame LoadFrame(const io::FrameEntry& frame, MaskSource& masks, const RunOptions& options) {
  LoadedFrame loaded = LoadImages(frame, options);
  SegmentFrame(masks, &loaded);
  return loaded;
}

namespace {

bool Skipped(const RunOptions& options, size_t index) {
  return options.skip && index >= options.skip->first &&
         (!options.skip->last || index < *options.skip->last);
}

// A keyframe's mask as <stamp>.png, 0 / 255, written whole or not at all.
void WriteKeyFrameMask(const std::string& folder, double timestamp, const cv::Mat& mask) {
  cv::Mat binary;
  cv::compare(mask, 0, binary, cv::CMP_NE);
  std::vector<uint8_t> png;
  const std::string path = fmt::format("{}/{:.6f}.png", folder, timestamp);
  if (!cv::imencode(".png", binary, png)) ThrowInput("cannot encode the keyframe mask {}", path);
  WriteFileAtomically(path, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()),
                      "keyframe mask");
}

bool StopRequested(const RunOptions& options) {
  return options.stop != nullptr && options.stop->load() != 0;
}

// Where the segmentation stages take their frames from: the loader of a sequence or the capture
// thread of a live source.
struct Upstream {
  SegmentationStage::Upstream next;
  SegmentationStage::StopUpstream stop;
  size_t first = 0;                       // the index of the first frame (--segment-every)
  std::optional<double> pace_from_stamp;  // --realtime: the first frame's stamp; nullopt: no pacing
  SegmentScheduleOptions schedule;        // --segment-every, with the pace when there is one
};

SegmentScheduleOptions ScheduleOptions(const RunOptions& options, const io::Sequence& sequence,
                                       size_t first, size_t last) {
  SegmentScheduleOptions schedule;
  schedule.every = options.segment_every;
  if (options.realtime && last > first + 1) {
    // The median interval of the range's frames: a data set's clock may have gaps.
    std::vector<double> intervals;
    for (size_t i = first + 1; i < last; ++i) {
      intervals.push_back(sequence.frames[i].timestamp - sequence.frames[i - 1].timestamp);
    }
    std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
    schedule.paced_interval_ms = std::max(0.0, 1000.0 * intervals[intervals.size() / 2]);
  }
  return schedule;
}

FrameRecord TrackOne(Tracker& tracker, const LoadedFrame& frame, const RunOptions& options) {
  FrameRecord record;
  record.index = frame.index;
  record.timestamp = frame.input.timestamp;
  record.mask_ms = frame.mask_ms;
  record.network_ms = frame.network_ms;
  record.crf_ms = frame.crf_ms;
  record.mask_fraction = frame.mask_fraction;
  record.segmented = frame.segment;
  record.report = TrackFrame(tracker, frame);
  if (!options.keyframe_mask_folder.empty() && !record.report.keyframe_mask.empty()) {
    WriteKeyFrameMask(options.keyframe_mask_folder, record.timestamp, record.report.keyframe_mask);
  }
  record.report.keyframe_mask.release();
  record.rss_mb = static_cast<double>(ResidentSetBytes()) / (1 << 20);
  spdlog::debug("frame {} ({:.6f}): {}, {} features, {} inliers, {:.1f} ms", record.index,
                record.timestamp, StateName(record.report.state), record.report.num_features,
                record.report.num_inliers, record.report.times.total_ms);
  return record;
}

// The frames of `upstream` through the tracker, segmented in threads of their own; returns when
// the upstream ends, when RunOptions::stop is set, or by throwing what a stage or the tracker
// threw, after the stage threads have stopped.
void TrackStream(const Upstream& upstream, Tracker& tracker, MaskSource& masks,
                 const RunOptions& options, Clock::time_point start, Progress* progress,
                 RunResult* result) {
  // A network source gets two stages, network then refinement (the CRF), so that on two
  // cores the CRF of frame k runs beside the network of frame k+1. The first stage decides
  // whether the source runs on a frame (--segment-every) and the frame carries the decision.
  SegmentSchedule schedule(upstream.schedule);
  const auto decide = [&schedule, first = upstream.first](LoadedFrame& f) {
    f.segment = schedule.Due(static_cast<size_t>(f.index) - first);
  };
  std::optional<SegmentationStage> network_stage;
  if (masks.Pipelined()) {
    network_stage.emplace(
        upstream.next, upstream.stop,
        [&masks, &decide, &schedule](LoadedFrame& f) {
          decide(f);
          if (!f.segment) return;
          PredictFrame(masks, &f);
          schedule.AddSegmentationMs(0, f.mask_ms);
        },
        options.queue_capacity);
  }
  SegmentationStage stage(
      [&] { return network_stage ? network_stage->Next() : upstream.next(); },
      [&] { network_stage ? network_stage->Stop() : upstream.stop(); },
      [&masks, &decide, &schedule, pipelined = masks.Pipelined()](LoadedFrame& f) {
        if (!pipelined) decide(f);
        if (!f.segment) return;
        const double before = f.mask_ms;
        pipelined ? RefineFrame(masks, &f) : SegmentFrame(masks, &f);
        schedule.AddSegmentationMs(pipelined ? 1 : 0, f.mask_ms - before);
      },
      options.queue_capacity);
  while (std::optional<LoadedFrame> frame = stage.Next()) {
    if (StopRequested(options)) {
      result->end = RunEnd::kInterrupted;
      result->end_message = fmt::format("stopped before frame {}", frame->index);
      return;
    }
    // Skipped frames are loaded (the loader reads the range in order) but never tracked.
    if (Skipped(options, static_cast<size_t>(frame->index))) continue;
    if (upstream.pace_from_stamp) {
      // Pacing is the one legitimate sleep: a frame is not given to the tracker before its
      // time on the data set's clock, counted from the first frame.
      const auto at =
          start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                      frame->input.timestamp - *upstream.pace_from_stamp));
      std::this_thread::sleep_until(at);
    }
    result->frames.push_back(TrackOne(tracker, *frame, options));
    schedule.AddTrackingMs(result->frames.back().report.times.total_ms);
    if (options.observer != nullptr) {
      options.observer->OnFrame(result->frames.back(), frame->input, tracker);
    }
    if (progress != nullptr) progress->Update(result->frames.size());
  }
}

// Frames result->first..last of the sequence, loaded in a thread of their own.
void TrackFrames(const io::Sequence& sequence, Tracker& tracker, MaskSource& masks,
                 const RunOptions& options, Clock::time_point start, Progress* progress,
                 RunResult* result) {
  // Outlives TrackStream's stages, which stop it when they stop; its destructor joins the
  // thread also when Track(), segmentation or loading threw.
  FrameLoader loader(
      sequence, result->first, result->last,
      [&options](const io::FrameEntry& f) { return LoadImages(f, options); },
      options.queue_capacity);
  Upstream upstream;
  upstream.next = [&loader] { return loader.Next(); };
  upstream.stop = [&loader] { loader.Stop(); };
  upstream.first = result->first;
  if (options.realtime) upstream.pace_from_stamp = sequence.frames[result->first].timestamp;
  upstream.schedule = ScheduleOptions(options, sequence, result->first, result->last);
  TrackStream(upstream, tracker, masks, options, start, progress, result);
}

// The end of every run: the tracker finished (local mapping drained, the map saved), an error
// in Finish() recorded unless the run had failed already, the trajectories collected.
void FinishRun(Tracker& tracker, Clock::time_point start, RunResult* result) {
  try {
    tracker.Finish();  // saving a map (--save-map) may fail on a full disk
  } catch (const std::exception& e) {
    if (result->end == RunEnd::kFailed) {
      spdlog::error("finishing the tracker after the error: {}", e.what());
    } else {
      result->end = RunEnd::kFailed;
      result->end_message = e.what();
      result->error = std::current_exception();
    }
  }
  result->wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  result->camera = tracker.CameraTrajectory();
  result->keyframes = tracker.KeyFrameTrajectory();
  result->graph = FinalKeyFrameGraph(tracker, result->keyframes);
  result->map = tracker.Summary();
}

}  // namespace

RunResult RunSequence(const io::Sequence& sequence, Tracker& tracker, MaskSource& masks,
                      const RunOptions& options) {
  options.Check();
  RunResult result;
  result.first = options.frames.first;
  result.last = options.frames.last.value_or(sequence.size());
  if (result.last > sequence.size() || result.first >= result.last) {
    ThrowInput("--frames: {}:{} is outside the sequence's {} frames (0:{})", result.first,
               result.last, sequence.size(), sequence.size());
  }
  for (size_t i = result.first; i < result.last; ++i) result.skipped += Skipped(options, i) ? 1 : 0;
  const size_t count = result.last - result.first - result.skipped;
  result.frames.reserve(count);
  const auto start = Clock::now();
  std::optional<Progress> progress;
  if (options.progress) progress.emplace("tracking", count, 2.0, "frames");
  try {
    TrackFrames(sequence, tracker, masks, options, start, progress ? &*progress : nullptr, &result);
  } catch (const std::exception& e) {
    // The frames before the error keep their poses: the tracker is finished as at the end.
    result.end = RunEnd::kFailed;
    result.end_message = e.what();
    result.error = std::current_exception();
  }
  if (progress) progress->Finish();
  FinishRun(tracker, start, &result);
  return result;
}

RunResult RunLive(io::LiveSource& source, Tracker& tracker, MaskSource& masks,
                  const RunOptions& options) {
  options.Check();
  if (options.frames.first != 0 || options.frames.last || options.skip || options.realtime) {
    ThrowInput(
        "{}: --frames, --skip-frames and --realtime are for recorded data; a live source runs "
        "in real time from its first frame",
        source.name());
  }
  LiveCaptureOptions capture_options;
  capture_options.queue_capacity = options.queue_capacity;
  capture_options.colour = options.colour;
  capture_options.image_size = options.image_size;
  capture_options.stop = options.stop;
  RunResult result;
  result.live.emplace();
  const auto start = Clock::now();
  std::optional<Progress> progress;
  // A live run has no known length: the progress line counts frames and their rate.
  if (options.progress) progress.emplace("tracking", 0, 2.0, "frames");
  // Said once the stop flag is in place (moslam run installs its handlers before calling).
  spdlog::info("{}: live, at most {} frames waiting for tracking; Ctrl-C ends the run",
               source.name(), options.queue_capacity);
  try {
    LiveCapture capture(source, capture_options);
    Upstream upstream;
    upstream.next = [&capture] { return capture.Next(); };
    upstream.stop = [&capture] { capture.Stop(); };
    // A live source's interval is not known ahead: --segment-every auto keeps up with tracking.
    upstream.schedule.every = options.segment_every;
    try {
      TrackStream(upstream, tracker, masks, options, start, progress ? &*progress : nullptr,
                  &result);
    } catch (...) {
      *result.live = capture.counts();
      throw;
    }
    *result.live = capture.counts();
    if (result.end == RunEnd::kCompleted && capture.stopped_by_flag()) {
      result.end = RunEnd::kInterrupted;
      result.end_message = fmt::format("stopped after frame {}", result.live->captured);
    }
  } catch (const std::exception& e) {
    result.end = RunEnd::kFailed;
    result.end_message = e.what();
    result.error = std::current_exception();
  }
  if (progress) progress->Finish();
  result.last = result.live->captured;
  if (result.live->dropped > 0) {
    spdlog::warn("{}: {} of {} frames dropped while tracking was busy (at most {} waited)",
                 source.name(), result.live->dropped, result.live->captured,
                 options.queue_capacity);
  } else {
    spdlog::info("{}: {} frames captured, none dropped", source.name(), result.live->captured);
  }
  FinishRun(tracker, start, &result);
  return result;
}

}  // namespace moslam::runner
