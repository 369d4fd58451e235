#include "moslam/io/video.h"

#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"

namespace moslam::io {
namespace {

namespace fs = std::filesystem;

void RequireFile(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) ThrowInFile(path, "is a folder, not a video file");
  if (!fs::exists(path, ec)) ThrowInFile(path, "no such video file");
}

// OpenCV's FFmpeg backend, which reads files; other backends (V4L2, GStreamer pipelines) take
// device names and strings that are not files.
cv::VideoCapture Open(const std::string& path) {
  RequireFile(path);
  cv::VideoCapture capture;
  try {
    capture.open(path, cv::CAP_FFMPEG);
  } catch (const cv::Exception& e) {
    ThrowInFile(path, fmt::format("cannot be opened as a video: {}", e.err));
  }
  if (!capture.isOpened()) {
    ThrowInFile(path, "cannot be opened as a video (not a video file OpenCV's FFmpeg reads)");
  }
  return capture;
}

}  // namespace

Sequence ReadVideo(const std::string& path, const VideoOptions& options) {
  if (!(options.rate_hz >= 0.0) || !std::isfinite(options.rate_hz)) {
    ThrowInFile(path, fmt::format("video rate must be a positive number of frames per second, "
                                  "got {}",
                                  options.rate_hz));
  }
  cv::VideoCapture capture = Open(path);
  Sequence sequence;
  sequence.name = fs::path(path).stem().string();
  sequence.root = path;
  sequence.sensor = SensorType::kMonocular;
  while (capture.grab()) {
    FrameEntry frame;
    frame.index = static_cast<int>(sequence.frames.size());
    frame.image_left = path;
    // The stamp of the frame just grabbed (its presentation time in the container).
    frame.timestamp = options.rate_hz > 0.0 ? frame.index / options.rate_hz
                                            : capture.get(cv::CAP_PROP_POS_MSEC) / 1000.0;
    if (!std::isfinite(frame.timestamp) ||
        (!sequence.frames.empty() && frame.timestamp <= sequence.frames.back().timestamp)) {
      ThrowInFile(path, fmt::format("frame {}: the container's time {} s does not follow the "
                                    "last frame's; give the frame rate (--rate HZ)",
                                    frame.index, frame.timestamp));
    }
    sequence.frames.push_back(frame);
  }
  if (sequence.frames.empty()) ThrowInFile(path, "the video has no frame OpenCV can decode");
  return sequence;
}

VideoReader::VideoReader(const std::string& path) : path_(path), capture_(Open(path)) {}

cv::Mat VideoReader::Read(int index, ColourMode mode) {
  if (index != next_) {
    // Seeking lands on the frame exactly with FFmpeg's frame-accurate seek of OpenCV >= 4.2.
    capture_.set(cv::CAP_PROP_POS_FRAMES, index);
    next_ = index;
  }
  cv::Mat frame;
  if (!capture_.read(frame) || frame.empty()) {
    ThrowInFile(path_, fmt::format("frame {} cannot be decoded", index));
  }
  ++next_;
  cv::Mat out;
  if (mode == ColourMode::kGrey) {
    if (frame.channels() == 1) return frame;
    // The decoded frame is BGR, as imread's colour images are.
    cv::cvtColor(frame, out, frame.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
    return out;
  }
  if (frame.channels() == 3) return frame;
  cv::cvtColor(frame, out, frame.channels() == 1 ? cv::COLOR_GRAY2BGR : cv::COLOR_BGRA2BGR);
  return out;
}

}  // namespace moslam::io
