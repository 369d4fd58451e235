// A fixed set of worker threads for data-parallel loops inside one call (the CRF's splat, blur,
// slice and update passes). Work is split into contiguous index ranges, one per thread; callers
// keep results independent of the split (each output element is computed by one thread, in a
// fixed order), so that the output is identical whatever the number of threads.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace moslam::semantic {

class ThreadPool {
 public:
  // `num_threads` >= 1 counts the calling thread: a pool of 1 runs everything inline.
  explicit ThreadPool(int num_threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int num_threads() const { return static_cast<int>(workers_.size()) + 1; }

  // Calls fn(begin, end) on disjoint ranges covering [0, n), one range per thread, and returns
  // when all have finished; an exception thrown by fn is rethrown then (the first range's
  // first). Not reentrant: fn must not call the pool.
  void ParallelFor(int64_t n, const std::function<void(int64_t, int64_t)>& fn);

 private:
  // Runs job_ for thread slot `slot` (0 is the caller).
  void RunSlot(int slot);
  void WorkerLoop(int slot);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  const std::function<void(int)>* job_ = nullptr;
  uint64_t generation_ = 0;
  int pending_ = 0;
  bool stop_ = false;
};

}  // namespace moslam::semantic
