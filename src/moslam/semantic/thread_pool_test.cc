#include "moslam/semantic/thread_pool.h"

#include <atomic>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace moslam::semantic {
namespace {

TEST(ThreadPool, ParallelForCoversEveryIndexOnce) {
  for (int threads : {1, 2, 3, 4}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.num_threads(), threads);
    for (int64_t n : {0, 1, 2, 7, 1000}) {
      std::vector<std::atomic<int>> hits(static_cast<size_t>(n));
      pool.ParallelFor(n, [&](int64_t begin, int64_t end) {
        for (int64_t i = begin; i < end; ++i) ++hits[static_cast<size_t>(i)];
      });
      for (int64_t i = 0; i < n; ++i) EXPECT_EQ(hits[static_cast<size_t>(i)], 1) << i;
    }
  }
}

TEST(ThreadPool, RethrowsAnExceptionAfterAllRangesFinish) {
  ThreadPool pool(2);
  std::atomic<int> finished{0};
  EXPECT_THROW(pool.ParallelFor(2,
                                [&](int64_t begin, int64_t) {
                                  if (begin == 1) throw std::runtime_error("range 1");
                                  ++finished;
                                }),
               std::runtime_error);
  EXPECT_EQ(finished, 1);
  // The pool still works afterwards.
  std::atomic<int> calls{0};
  pool.ParallelFor(10, [&](int64_t begin, int64_t end) { calls += static_cast<int>(end - begin); });
  EXPECT_EQ(calls, 10);
}

}  // namespace
}  // namespace moslam::semantic
