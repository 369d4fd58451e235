// What the process itself uses, read from Linux's /proc (proc(5)): for long runs that log their
// memory over time (moslam run's frames.csv, docs/ROBUSTNESS.md "Long runs").
#pragma once

#include <cstdint>

namespace moslam {

// The resident set size of this process in bytes (/proc/self/statm, resident pages times the
// page size); 0 where /proc cannot be read (not Linux, or a sandbox without it).
uint64_t ResidentSetBytes();

}  // namespace moslam
