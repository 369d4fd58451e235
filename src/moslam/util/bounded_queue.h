// A typed, bounded, blocking queue between two threads, with an explicit stop.
//
// Producers block in Push() while the queue is full, consumers in Pop() while it is empty; both
// wait on condition variables, never by polling. Close() ends the exchange from either side: it
// wakes every waiter, later Push() calls return false (the item is dropped), and Pop() keeps
// returning the queued items and then nullopt. The bound is what keeps a fast producer (image
// loading) from running arbitrarily far ahead of a slow consumer (tracking) and filling memory.
//
//   BoundedQueue<Item> queue(4);
//   producer: for (...) if (!queue.Push(item)) break;  queue.Close();
//   consumer: while (std::optional<Item> item = queue.Pop()) { ... }
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>
#include <utility>

#include "moslam/util/check.h"

namespace moslam {

template <typename T>
class BoundedQueue {
 public:
  // capacity: the most items held at once (> 0).
  explicit BoundedQueue(size_t capacity) : capacity_(capacity) {
    MOSLAM_CHECK(capacity > 0) << "a bounded queue needs a capacity of at least 1";
  }
  BoundedQueue(const BoundedQueue&) = delete;
  BoundedQueue& operator=(const BoundedQueue&) = delete;

  // Waits for room, then appends. Returns false (dropping `item`) when the queue is closed.
  bool Push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_full_.wait(lock, [this] { return closed_ || items_.size() < capacity_; });
    if (closed_) return false;
    items_.push_back(std::move(item));
    lock.unlock();
    not_empty_.notify_one();
    return true;
  }

  // Appends only when there is room and the queue is open; never waits.
  bool TryPush(T item) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (closed_ || items_.size() >= capacity_) return false;
      items_.push_back(std::move(item));
    }
    not_empty_.notify_one();
    return true;
  }

  // Waits for an item. nullopt once the queue is closed and drained.
  std::optional<T> Pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait(lock, [this] { return closed_ || !items_.empty(); });
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    lock.unlock();
    not_full_.notify_one();
    return item;
  }

  // The front item if there is one; never waits.
  std::optional<T> TryPop() {
    std::unique_lock<std::mutex> lock(mutex_);
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    lock.unlock();
    not_full_.notify_one();
    return item;
  }

  // Explicit stop: wakes all waiters; no more pushes; queued items can still be popped.
  void Close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    not_full_.notify_all();
    not_empty_.notify_all();
  }

  bool closed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return closed_;
  }
  size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }
  size_t capacity() const { return capacity_; }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable not_full_;
  std::condition_variable not_empty_;
  std::deque<T> items_;
  bool closed_ = false;
};

}  // namespace moslam
