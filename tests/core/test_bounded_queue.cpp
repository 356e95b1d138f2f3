// The hand-over between the reading thread and the odometry: order kept, the producer held back at
// the bound, and either side able to end it without the other hanging.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

#include "core/bounded_queue.hpp"

namespace eds {
namespace {

TEST(BoundedQueue, KeepsOrderAndHoldsTheProducerAtTheBound) {
  BoundedQueue<int> q(2);
  std::atomic<int> pushed{0};
  std::thread producer([&] {
    for (int i = 0; i < 100; ++i) {
      EXPECT_TRUE(q.push(i));
      ++pushed;
    }
    q.close();
  });
  // Nothing is popped yet: the producer stops at the bound (2 queued, the third push waiting).
  while (pushed < 2) std::this_thread::yield();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(pushed.load(), 2);
  int v = -1, expected = 0;
  while (q.pop(v)) EXPECT_EQ(v, expected++);
  producer.join();
  EXPECT_EQ(expected, 100);
}

TEST(BoundedQueue, TheProducersErrorReachesTheConsumerAfterWhatCameBefore) {
  BoundedQueue<int> q(4);
  std::thread producer([&] {
    q.push(7);
    q.fail(std::make_exception_ptr(std::runtime_error("bad input")));
  });
  producer.join();
  int v = 0;
  ASSERT_TRUE(q.pop(v));
  EXPECT_EQ(v, 7);
  EXPECT_THROW(q.pop(v), std::runtime_error);
}

TEST(BoundedQueue, CancelReleasesAProducerWaitingForRoom) {
  BoundedQueue<int> q(1);
  std::atomic<bool> refused{false};
  std::thread producer([&] {
    q.push(1);
    refused = !q.push(2);  // waits: the queue is full
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  q.cancel();
  producer.join();
  EXPECT_TRUE(refused);
  EXPECT_THROW(BoundedQueue<int>(0), std::invalid_argument);
}

}  // namespace
}  // namespace eds
