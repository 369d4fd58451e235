// SIGINT and SIGTERM during `moslam run`: instead of ending the process with nothing written,
// the signal is stored and the run loop (RunOptions::stop) ends after the frame in hand, the
// tracker is finished and every output of the frames tracked so far is written, with summary.json
// saying "interrupted" (issue 31). A second signal of either kind ends the process at once, as
// the default action would have (the handlers are installed with SA_RESETHAND).
#pragma once

#include <atomic>

namespace moslam::runner {

class ScopedStopSignals {
 public:
  // Installs the handlers; at most one instance at a time (a broken invariant otherwise).
  ScopedStopSignals();
  // Restores the handlers that were there before.
  ~ScopedStopSignals();
  ScopedStopSignals(const ScopedStopSignals&) = delete;
  ScopedStopSignals& operator=(const ScopedStopSignals&) = delete;

  // The number of the signal received, 0 while none was: what RunOptions::stop points at.
  const std::atomic<int>* flag() const;
  int received() const { return flag()->load(); }
};

// "SIGINT", "SIGTERM", or "a signal".
const char* SignalName(int signal);

}  // namespace moslam::runner
