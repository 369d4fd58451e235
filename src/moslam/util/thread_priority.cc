#include "moslam/util/thread_priority.h"

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#endif

namespace moslam::util {

bool LowerCurrentThreadPriority(int increment) {
  if (increment <= 0) return true;
#if defined(__linux__)
  // POSIX says nice values belong to processes; Linux keeps them per thread (man 7 sched, "the
  // nice value is a per-thread attribute"), addressed by the thread id.
  const auto tid = static_cast<id_t>(syscall(SYS_gettid));
  errno = 0;
  const int current = getpriority(PRIO_PROCESS, tid);
  if (current == -1 && errno != 0) return false;
  const int target = current + increment > 19 ? 19 : current + increment;
  return setpriority(PRIO_PROCESS, tid, target) == 0;
#else
  return false;
#endif
}

}  // namespace moslam::util
