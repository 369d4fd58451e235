// A latest-value slot between two threads: the producer puts, replacing what the consumer has not
// taken yet (that older value is dropped), and never waits for the consumer. The live viewer's
// tracking thread hands its snapshots to the server thread through one, so a slow server or
// browser costs frames shown, never tracking time.
#pragma once

#include <mutex>
#include <optional>
#include <utility>

namespace moslam::viewer {

template <typename T>
class LatestSlot {
 public:
  // Stores `value`; returns true when it replaced one that was never taken (dropped).
  bool Put(T value) {
    std::lock_guard<std::mutex> lock(mutex_);
    const bool dropped = value_.has_value();
    value_ = std::move(value);
    return dropped;
  }
  // The value, emptying the slot; nullopt when there is none.
  std::optional<T> Take() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::optional<T> value = std::move(value_);
    value_.reset();
    return value;
  }
  bool Empty() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return !value_.has_value();
  }

 private:
  mutable std::mutex mutex_;
  std::optional<T> value_;
};

}  // namespace moslam::viewer
