#include "moslam/util/thread_priority.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace moslam::util {
namespace {

#if defined(__linux__)
int OwnNice() { return getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid))); }

TEST(ThreadPriority, LowersOnlyTheCallingThread) {
  const int main_nice = OwnNice();
  int worker_before = 0, worker_after = 0, child_nice = 0;
  bool ok = false;
  std::thread worker([&] {
    worker_before = OwnNice();
    ok = LowerCurrentThreadPriority(5);
    worker_after = OwnNice();
    // A thread started by a lowered thread inherits its nice value.
    std::thread child([&] { child_nice = OwnNice(); });
    child.join();
  });
  worker.join();
  ASSERT_TRUE(ok);
  EXPECT_EQ(worker_after, std::min(19, worker_before + 5));
  EXPECT_EQ(child_nice, worker_after);
  EXPECT_EQ(OwnNice(), main_nice);
}

TEST(ThreadPriority, ZeroIsANoOp) {
  const int before = OwnNice();
  EXPECT_TRUE(LowerCurrentThreadPriority(0));
  EXPECT_EQ(OwnNice(), before);
}
#endif

}  // namespace
}  // namespace moslam::util
