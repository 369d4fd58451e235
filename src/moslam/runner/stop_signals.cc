#include "moslam/runner/stop_signals.h"

#include <csignal>

#include "moslam/util/check.h"

namespace moslam::runner {
namespace {

// A lock-free atomic is safe to store from a signal handler (the only thing the handler does).
std::atomic<int> g_signal{0};
std::atomic<bool> g_installed{false};
static_assert(std::atomic<int>::is_always_lock_free);

struct sigaction g_previous_int;
struct sigaction g_previous_term;

extern "C" void StoreSignal(int signal) { g_signal.store(signal); }

}  // namespace

ScopedStopSignals::ScopedStopSignals() {
  MOSLAM_CHECK(!g_installed.exchange(true)) << "two ScopedStopSignals at once";
  g_signal.store(0);
  struct sigaction action {};
  action.sa_handler = StoreSignal;
  sigemptyset(&action.sa_mask);
  // SA_RESETHAND: the first signal is stored, the second gets the default action (ends the
  // process), so that a user who presses Ctrl-C twice is never kept waiting.
  action.sa_flags = SA_RESETHAND | SA_RESTART;
  sigaction(SIGINT, &action, &g_previous_int);
  sigaction(SIGTERM, &action, &g_previous_term);
}

ScopedStopSignals::~ScopedStopSignals() {
  sigaction(SIGINT, &g_previous_int, nullptr);
  sigaction(SIGTERM, &g_previous_term, nullptr);
  g_installed.store(false);
}

const std::atomic<int>* ScopedStopSignals::flag() const { return &g_signal; }

const char* SignalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "a signal";
  }
}

}  // namespace moslam::runner
