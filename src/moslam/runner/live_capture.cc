#include "moslam/runner/live_capture.h"

#include <algorithm>
#include <utility>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"

namespace moslam::runner {
namespace {

// A camera's BGR or grey image as the tracker wants it (io::LoadImage's conventions).
cv::Mat ToColourMode(const cv::Mat& image, io::ColourMode mode) {
  if (image.empty()) return image;
  cv::Mat out;
  if (mode == io::ColourMode::kGrey) {
    if (image.channels() == 1) return image;
    cv::cvtColor(image, out, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
    return out;
  }
  if (image.channels() == 3) return image;
  cv::cvtColor(image, out, image.channels() == 1 ? cv::COLOR_GRAY2BGR : cv::COLOR_BGRA2BGR);
  return out;
}

}  // namespace

void LiveCaptureOptions::Check() const {
  if (queue_capacity == 0) ThrowInput("live.queue_capacity: must be > 0");
  if (image_size.width < 0 || image_size.height < 0) {
    ThrowInput("live.image_size: must not be negative, got {}x{}", image_size.width,
               image_size.height);
  }
}

LiveCapture::LiveCapture(io::LiveSource& source, const LiveCaptureOptions& options)
    : source_(source), options_(options), queue_((options.Check(), options.queue_capacity)) {
  thread_ = std::thread([this] { Run(); });
}

LiveCapture::~LiveCapture() {
  Stop();
  if (thread_.joinable()) thread_.join();
}

LiveCounts LiveCapture::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_;
}

std::optional<LoadedFrame> LiveCapture::Next() {
  std::optional<LoadedFrame> frame = queue_.Pop();
  if (!frame) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (error_) std::rethrow_exception(error_);
  }
  return frame;
}

LoadedFrame LiveCapture::Convert(io::LiveFrame frame, size_t index) const {
  const std::string name = source_.name();
  const cv::Mat& left = frame.images.left;
  if (left.empty()) ThrowInFile(name, fmt::format("frame {}: no image", index));
  if (!options_.image_size.empty() && left.size() != options_.image_size) {
    ThrowInFile(name, fmt::format("frame {}: the image is {}x{}, but Camera.width x "
                                  "Camera.height in the settings are {}x{}",
                                  index, left.cols, left.rows, options_.image_size.width,
                                  options_.image_size.height));
  }
  auto entry = std::make_shared<io::FrameEntry>();
  entry->index = static_cast<int>(index);
  entry->timestamp = frame.timestamp;
  entry->image_left = name;  // what errors about this frame name
  LoadedFrame loaded;
  loaded.index = entry->index;
  loaded.owned_entry = entry;
  loaded.entry = entry.get();
  loaded.input.timestamp = frame.timestamp;
  loaded.input.image = ToColourMode(left, options_.colour);
  loaded.input.right = ToColourMode(frame.images.right, options_.colour);
  loaded.input.depth = std::move(frame.images.depth);
  return loaded;
}

// Drops the oldest waiting frame when the queue is full. Only this thread pushes, so after the
// drop there is room and Push() does not wait; it fails only when the queue was closed.
void LiveCapture::Hand(LoadedFrame frame) {
  if (queue_.size() >= queue_.capacity()) {
    if (std::optional<LoadedFrame> old = queue_.TryPop()) {
      std::lock_guard<std::mutex> lock(mutex_);
      ++counts_.dropped;
      spdlog::debug("{}: frame {} dropped (tracking busy)", source_.name(), old->index);
    }
  }
  if (!queue_.Push(std::move(frame))) return;
  std::lock_guard<std::mutex> lock(mutex_);
  counts_.max_queued = std::max(counts_.max_queued, queue_.size());
}

void LiveCapture::Run() {
  try {
    for (size_t index = 0; !queue_.closed(); ++index) {
      std::optional<io::LiveFrame> frame = source_.Grab();
      if (options_.stop != nullptr && options_.stop->load() != 0) {
        stopped_by_flag_ = true;
        break;
      }
      if (!frame) break;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        ++counts_.captured;
      }
      Hand(Convert(std::move(*frame), index));
    }
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = std::current_exception();
  }
  queue_.Close();
}

}  // namespace moslam::runner
