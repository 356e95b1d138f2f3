#pragma once
// A blocking queue of bounded length between one producer and one consumer thread: the producer waits
// while it is full (the consumer sets the pace, memory stays bounded), the consumer while it is empty.
// Either side can end it: the producer by close() or fail(error) (the consumer rethrows the error),
// the consumer by cancel() (the producer's next push returns false).
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <utility>

namespace eds {

template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(std::size_t capacity) : capacity_(capacity) {
    if (capacity_ == 0) throw std::invalid_argument("BoundedQueue: capacity must be at least 1");
  }

  // Waits for room; false (item dropped) when the consumer cancelled.
  bool push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_full_.wait(lock, [&] { return items_.size() < capacity_ || cancelled_; });
    if (cancelled_) return false;
    items_.push_back(std::move(item));
    not_empty_.notify_one();
    return true;
  }

  void close() { end(nullptr); }
  void fail(std::exception_ptr error) { end(std::move(error)); }

  // Waits for an item; false once the producer closed the queue and it is empty. Rethrows the
  // producer's error after the items queued before it.
  bool pop(T& out) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait(lock, [&] { return !items_.empty() || closed_; });
    if (items_.empty()) {
      if (error_) std::rethrow_exception(error_);
      return false;
    }
    out = std::move(items_.front());
    items_.pop_front();
    not_full_.notify_one();
    return true;
  }

  void cancel() {
    const std::lock_guard<std::mutex> lock(mutex_);
    cancelled_ = true;
    items_.clear();
    not_full_.notify_all();
  }

 private:
  void end(std::exception_ptr error) {
    const std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    error_ = std::move(error);
    not_empty_.notify_all();
  }

  std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
  std::deque<T> items_;
  std::size_t capacity_;
  bool closed_ = false, cancelled_ = false;
  std::exception_ptr error_;
};

}  // namespace eds
