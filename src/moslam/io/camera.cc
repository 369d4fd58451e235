#include "moslam/io/camera.h"

#include <sys/stat.h>

#include <cmath>
#include <utility>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/videoio.hpp>

#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam::io {
namespace {

// Why a path cannot be a camera, before OpenCV tries it (OpenCV only says "cannot open").
void RequireCharacterDevice(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    ThrowInFile(path, "no such camera device (is it plugged in? `ls /dev/video*` lists them)");
  }
  if (!S_ISCHR(st.st_mode)) {
    ThrowInFile(path, "is not a camera device (a V4L2 character device such as /dev/video0)");
  }
}

cv::VideoCapture OpenDevice(const std::string& path, const CameraOptions& options) {
  RequireCharacterDevice(path);
  cv::VideoCapture capture;
  try {
    capture.open(path, cv::CAP_V4L2);
  } catch (const cv::Exception& e) {
    ThrowInFile(path, fmt::format("cannot be opened as a V4L2 camera: {}", e.err));
  }
  if (!capture.isOpened()) {
    ThrowInFile(path,
                "cannot be opened as a V4L2 camera (busy, no read permission, or not a capture "
                "device)");
  }
  if (!options.size.empty()) {
    const int width = options.side_by_side ? 2 * options.size.width : options.size.width;
    capture.set(cv::CAP_PROP_FRAME_WIDTH, width);
    capture.set(cv::CAP_PROP_FRAME_HEIGHT, options.size.height);
    const cv::Size got(static_cast<int>(capture.get(cv::CAP_PROP_FRAME_WIDTH)),
                       static_cast<int>(capture.get(cv::CAP_PROP_FRAME_HEIGHT)));
    if (got != cv::Size(width, options.size.height)) {
      ThrowInFile(path, fmt::format("delivers {}x{} frames, not the {}x{} the settings' "
                                    "Camera.width x Camera.height ask{}",
                                    got.width, got.height, width, options.size.height,
                                    options.side_by_side ? " (two halves side by side)" : ""));
    }
  }
  if (options.fps > 0.0) capture.set(cv::CAP_PROP_FPS, options.fps);
  return capture;
}

class Camera : public LiveSource {
 public:
  explicit Camera(const CameraOptions& options) : side_by_side_(options.side_by_side) {
    for (const std::string& device : options.devices) {
      paths_.push_back(CameraDevicePath(device));
      captures_.push_back(OpenDevice(paths_.back(), options));
    }
    const cv::VideoCapture& first = captures_.front();
    size_ = cv::Size(static_cast<int>(first.get(cv::CAP_PROP_FRAME_WIDTH)),
                     static_cast<int>(first.get(cv::CAP_PROP_FRAME_HEIGHT)));
    if (side_by_side_) size_.width /= 2;
    spdlog::info("camera {}: {}x{}{} at {} frames/s", name(), size_.width, size_.height,
                 side_by_side_ ? " per half" : "", first.get(cv::CAP_PROP_FPS));
  }

  std::optional<LiveFrame> Grab() override {
    // Both devices grab before either decodes, so that the pair is as close in time as the
    // devices allow.
    for (size_t i = 0; i < captures_.size(); ++i) {
      if (!captures_[i].grab()) ThrowInFile(paths_[i], "delivered no frame (unplugged?)");
    }
    LiveFrame frame;
    last_stamp_ = frame.timestamp = clock_.NextAfter(last_stamp_);
    std::vector<cv::Mat> images(captures_.size());
    for (size_t i = 0; i < captures_.size(); ++i) {
      if (!captures_[i].retrieve(images[i]) || images[i].empty()) {
        ThrowInFile(paths_[i], "a frame could not be decoded");
      }
    }
    if (side_by_side_) {
      const cv::Mat& whole = images.front();
      const int half = whole.cols / 2;
      frame.images.left = whole.colRange(0, half).clone();
      frame.images.right = whole.colRange(half, 2 * half).clone();
    } else {
      frame.images.left = images.front();
      if (images.size() == 2) frame.images.right = images[1];
    }
    if (!frame.images.right.empty() && frame.images.right.size() != frame.images.left.size()) {
      ThrowInFile(paths_.back(), fmt::format("delivers {}x{} frames, the left camera {}x{}",
                                             frame.images.right.cols, frame.images.right.rows,
                                             frame.images.left.cols, frame.images.left.rows));
    }
    return frame;
  }

  SensorType sensor() const override {
    return side_by_side_ || captures_.size() == 2 ? SensorType::kStereo : SensorType::kMonocular;
  }
  std::string name() const override {
    return paths_.size() == 2 ? paths_[0] + "," + paths_[1] : paths_[0];
  }
  cv::Size image_size() const override { return size_; }

 private:
  bool side_by_side_ = false;
  std::vector<std::string> paths_;
  std::vector<cv::VideoCapture> captures_;
  cv::Size size_;
  LiveClock clock_;
  double last_stamp_ = 0.0;
};

}  // namespace

void CameraOptions::Check() const {
  if (devices.empty() || devices.size() > 2) {
    ThrowInput("camera: one device (mono, or stereo side by side) or two (stereo) expected, got {}",
               devices.size());
  }
  for (const std::string& device : devices) {
    if (Trim(device).empty()) ThrowInput("camera: an empty device name");
  }
  if (side_by_side && devices.size() != 1) {
    ThrowInput("camera: side-by-side stereo takes one device, got {}", devices.size());
  }
  if (size.width < 0 || size.height < 0) {
    ThrowInput("camera: size must not be negative, got {}x{}", size.width, size.height);
  }
  if (!(fps >= 0.0) || !std::isfinite(fps)) {
    ThrowInput("camera: fps must be >= 0 frames per second, got {}", fps);
  }
}

std::string CameraDevicePath(const std::string& device) {
  const auto index = ParseInt(device);
  return index && *index >= 0 ? fmt::format("/dev/video{}", *index) : device;
}

std::unique_ptr<LiveSource> OpenCamera(const CameraOptions& options) {
  options.Check();
  return std::make_unique<Camera>(options);
}

}  // namespace moslam::io
