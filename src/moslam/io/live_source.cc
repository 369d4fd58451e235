#include "moslam/io/live_source.h"

#include <algorithm>

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

}  // namespace moslam::io
