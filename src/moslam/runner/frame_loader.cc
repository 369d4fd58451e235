#include "moslam/runner/frame_loader.h"

#include <spdlog/spdlog.h>

namespace moslam::runner {

FrameLoader::FrameLoader(const io::Sequence& sequence, size_t first, size_t last, LoadFunction load,
                         size_t queue_capacity)
    : load_(std::move(load)), queue_(queue_capacity) {
  thread_ = std::thread([this, &sequence, first, last] { Run(sequence, first, last); });
}

FrameLoader::~FrameLoader() {
  queue_.Close();  // wakes the loader if it waits for room
  if (thread_.joinable()) thread_.join();
}

void FrameLoader::Run(const io::Sequence& sequence, size_t first, size_t last) {
  try {
    for (size_t i = first; i < last; ++i) {
      if (!queue_.Push(load_(sequence.frames[i]))) return;  // closed by the consumer
    }
  } catch (...) {
    std::lock_guard<std::mutex> lock(error_mutex_);
    error_ = std::current_exception();
  }
  queue_.Close();
}

std::optional<LoadedFrame> FrameLoader::Next() {
  std::optional<LoadedFrame> frame = queue_.Pop();
  if (frame) return frame;
  std::lock_guard<std::mutex> lock(error_mutex_);
  if (error_) std::rethrow_exception(error_);
  return std::nullopt;
}

}  // namespace moslam::runner
