// A live source of frames (`moslam run --dataset camera|kinect`): a camera that delivers frames
// at its own pace whether or not anyone takes them. Unlike a Sequence, there is no list of frames
// to read ahead: the runner's capture thread (runner/live_capture.h) calls Grab() in a loop and
// drops the frames that tracking has no time for. Tests drive the runner with fake sources.
#pragma once

#include <chrono>
#include <functional>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "moslam/io/image.h"
#include "moslam/io/sequence.h"

namespace moslam::io {

struct LiveFrame {
  double timestamp = 0.0;  // seconds; strictly increasing (cameras: Unix time at capture)
  // left: BGR (CV_8UC3) or grey (CV_8UC1), converted by the runner as the tracker wants;
  // right: stereo only; depth: RGB-D only, CV_32FC1 metres (0: no measurement).
  FrameImages images;
};

class LiveSource {
 public:
  virtual ~LiveSource() = default;
  // Waits for the next frame (a camera: at most about one frame interval). nullopt when the
  // source has no more frames (a fake's last one). A device that fails (unplugged, stopped
  // delivering) throws InputError naming it. Called by one thread at a time.
  virtual std::optional<LiveFrame> Grab() = 0;
  virtual SensorType sensor() const = 0;
  // What the source is, for messages and summary.json: "/dev/video0", "kinect:0".
  virtual std::string name() const = 0;
  // The size of the frames' left image, known once the source is open (0x0: unknown).
  virtual cv::Size image_size() const = 0;
};

// Unix time in seconds that never goes back: the system clock when `start` was taken plus the
// steady clock since, so that a clock adjustment during a run cannot reorder stamps.
class LiveClock {
 public:
  LiveClock();
  double Now() const;
  // Now(), or a microsecond after `last` when Now() is not later (two devices read at once).
  double NextAfter(double last) const;

 private:
  std::chrono::steady_clock::time_point start_;
  double start_unix_s_ = 0.0;
};

// A recorded sequence played as a live source (`moslam run --live`): frame k is delivered at its
// timestamp counted from the first frame (divided by `speed`), whether or not the last one was
// taken, as a camera delivers; frames keep their stamps, so the ATE against the sequence's ground
// truth still applies. `load` reads a frame's images (in the capture thread); a frame whose
// loading is late is delivered late, not skipped. The sleep is the source's own pacing.
class ReplaySource : public LiveSource {
 public:
  using Load = std::function<FrameImages(const FrameEntry&)>;
  // Keeps a copy of `sequence` (its frame list, not images). speed > 0.
  ReplaySource(Sequence sequence, Load load, double speed = 1.0);
  std::optional<LiveFrame> Grab() override;
  SensorType sensor() const override { return sequence_.sensor; }
  std::string name() const override { return sequence_.root; }
  cv::Size image_size() const override { return {}; }

 private:
  const Sequence sequence_;
  Load load_;
  double speed_ = 1.0;
  size_t next_ = 0;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace moslam::io
