#include "moslam/util/bounded_queue.h"

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace moslam {
namespace {

TEST(BoundedQueueTest, KeepsOrderAndMovesOnlyTypes) {
  BoundedQueue<std::unique_ptr<int>> queue(3);
  EXPECT_TRUE(queue.Push(std::make_unique<int>(1)));
  EXPECT_TRUE(queue.Push(std::make_unique<int>(2)));
  EXPECT_EQ(queue.size(), 2u);
  EXPECT_EQ(*queue.Pop().value(), 1);
  EXPECT_EQ(*queue.Pop().value(), 2);
  EXPECT_FALSE(queue.TryPop().has_value());
}

TEST(BoundedQueueTest, TryPushRefusesWhenFull) {
  BoundedQueue<int> queue(2);
  EXPECT_TRUE(queue.TryPush(1));
  EXPECT_TRUE(queue.TryPush(2));
  EXPECT_FALSE(queue.TryPush(3));
  EXPECT_EQ(queue.size(), 2u);
  EXPECT_EQ(queue.Pop().value(), 1);
  EXPECT_TRUE(queue.TryPush(3));
}

TEST(BoundedQueueTest, CloseDrainsThenEnds) {
  BoundedQueue<int> queue(4);
  queue.Push(7);
  queue.Push(8);
  queue.Close();
  EXPECT_TRUE(queue.closed());
  EXPECT_FALSE(queue.Push(9));
  EXPECT_FALSE(queue.TryPush(9));
  EXPECT_EQ(queue.Pop().value(), 7);
  EXPECT_EQ(queue.Pop().value(), 8);
  EXPECT_FALSE(queue.Pop().has_value());
}

TEST(BoundedQueueTest, CloseWakesABlockedConsumer) {
  BoundedQueue<int> queue(1);
  std::optional<int> popped = 42;
  std::thread consumer([&] { popped = queue.Pop(); });  // blocks: the queue is empty
  queue.Close();
  consumer.join();
  EXPECT_FALSE(popped.has_value());
}

TEST(BoundedQueueTest, CloseWakesABlockedProducer) {
  BoundedQueue<int> queue(1);
  ASSERT_TRUE(queue.Push(1));
  std::atomic<int> result{-1};
  std::thread producer([&] { result = queue.Push(2) ? 1 : 0; });  // blocks: the queue is full
  queue.Close();
  producer.join();
  EXPECT_EQ(result.load(), 0);
  EXPECT_EQ(queue.Pop().value(), 1);  // what was queued before the stop is still delivered
  EXPECT_FALSE(queue.Pop().has_value());
}

TEST(BoundedQueueTest, ProducerConsumerDeliverEverythingInOrderWithinTheBound) {
  constexpr int kCount = 2000;
  constexpr size_t kCapacity = 3;
  BoundedQueue<int> queue(kCapacity);
  std::atomic<size_t> max_size{0};
  std::thread producer([&] {
    for (int i = 0; i < kCount; ++i) {
      ASSERT_TRUE(queue.Push(i));
      size_t seen = queue.size();
      size_t previous = max_size.load();
      while (seen > previous && !max_size.compare_exchange_weak(previous, seen)) {
      }
    }
    queue.Close();
  });
  std::vector<int> received;
  while (std::optional<int> item = queue.Pop()) received.push_back(*item);
  producer.join();
  ASSERT_EQ(received.size(), static_cast<size_t>(kCount));
  for (int i = 0; i < kCount; ++i) EXPECT_EQ(received[i], i);
  EXPECT_LE(max_size.load(), kCapacity);
}

TEST(BoundedQueueDeathTest, ZeroCapacityIsABug) {
  EXPECT_DEATH(BoundedQueue<std::string> queue(0), "capacity");
}

}  // namespace
}  // namespace moslam
