#include "moslam/semantic/thread_pool.h"

#include <algorithm>
#include <exception>

#include "moslam/util/check.h"

namespace moslam::semantic {

ThreadPool::ThreadPool(int num_threads) {
  MOSLAM_CHECK_GE(num_threads, 1);
  for (int slot = 1; slot < num_threads; ++slot) {
    workers_.emplace_back([this, slot] { WorkerLoop(slot); });
  }
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

void ThreadPool::WorkerLoop(int slot) {
  uint64_t seen = 0;
  while (true) {
    const std::function<void(int)>* job = nullptr;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      job = job_;
    }
    (*job)(slot);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (--pending_ == 0) done_.notify_one();
    }
  }
}

void ThreadPool::RunSlot(int slot) { (*job_)(slot); }

void ThreadPool::ParallelFor(int64_t n, const std::function<void(int64_t, int64_t)>& fn) {
  if (n <= 0) return;
  const int64_t threads = std::min<int64_t>(num_threads(), n);
  if (threads == 1) {
    fn(0, n);
    return;
  }
  // An exception in any range is rethrown here, after all ranges have finished (the first by
  // range order, so that the error does not depend on timing).
  std::vector<std::exception_ptr> errors(static_cast<size_t>(threads));
  const std::function<void(int)> job = [&](int slot) {
    if (slot >= threads) return;
    try {
      fn(n * slot / threads, n * (slot + 1) / threads);
    } catch (...) {
      errors[static_cast<size_t>(slot)] = std::current_exception();
    }
  };
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = &job;
    pending_ = static_cast<int>(workers_.size());
    ++generation_;
  }
  start_.notify_all();
  RunSlot(0);
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return pending_ == 0; });
  job_ = nullptr;
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
}

}  // namespace moslam::semantic
