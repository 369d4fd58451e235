// Per-thread scheduling priority: lets background work (local mapping, loop closing) yield the
// cores to latency-bound work (tracking, segmentation) on a small machine.
#pragma once

namespace moslam::util {

// Raises the calling thread's nice value by `increment` (0 to 19; 0 does nothing). On Linux a
// thread's nice value is its own (setpriority on its thread id) and threads it starts inherit it.
// Returns false where the platform cannot do it, or the call failed; never throws: priority is a
// hint, and work goes on at the old one.
bool LowerCurrentThreadPriority(int increment);

}  // namespace moslam::util
