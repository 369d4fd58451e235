#include "moslam/io/live_source.h"

#include <algorithm>
#include <cmath>
#include <thread>
#include <utility>

#include "moslam/util/error.h"

namespace moslam::io {

LiveClock::LiveClock()
    : start_(std::chrono::steady_clock::now()),
      start_unix_s_(
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
              .count()) {}

double LiveClock::Now() const {
  return start_unix_s_ +
         std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

double LiveClock::NextAfter(double last) const { return std::max(Now(), last + 1e-6); }

ReplaySource::ReplaySource(Sequence sequence, Load load, double speed)
    : sequence_(std::move(sequence)), load_(std::move(load)), speed_(speed) {
  if (!(speed > 0.0) || !std::isfinite(speed)) {
    ThrowInput("replay speed: must be > 0, got {}", speed);
  }
}

std::optional<LiveFrame> ReplaySource::Grab() {
  if (next_ >= sequence_.size()) return std::nullopt;
  const FrameEntry& frame = sequence_.frames[next_];
  if (next_ == 0) start_ = std::chrono::steady_clock::now();
  const double due_s = (frame.timestamp - sequence_.frames.front().timestamp) / speed_;
  std::this_thread::sleep_until(start_ + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                             std::chrono::duration<double>(due_s)));
  ++next_;
  LiveFrame live;
  live.timestamp = frame.timestamp;
  live.images = load_(frame);
  return live;
}

}  // namespace moslam::io
