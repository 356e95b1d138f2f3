#include "system/release_queue.hpp"

#include <algorithm>

namespace eds {

void ReleaseQueue::push(ReleasedItem item) {
  const std::lock_guard<std::mutex> lock(mutex_);
  queued_events_ += item.events.size();
  queued_frames_ += item.frame;
  items_.push_back(std::move(item));
  while (queued_events_ > max_events_) dropOldest(false);  // the chunks hold all queued events
  while (queued_frames_ > max_frames_) dropOldest(true);
  ready_.notify_one();
}

void ReleaseQueue::dropOldest(bool frame) {
  const auto it =
      std::find_if(items_.begin(), items_.end(), [&](const ReleasedItem& i) { return i.frame == frame; });
  queued_events_ -= it->events.size();
  dropped_events_ += it->events.size();
  queued_frames_ -= frame, dropped_frames_ += frame;
  items_.erase(it);
}

void ReleaseQueue::close() {
  const std::lock_guard<std::mutex> lock(mutex_);
  closed_ = true;
  ready_.notify_one();
}

void ReleaseQueue::fail(std::exception_ptr error) {
  const std::lock_guard<std::mutex> lock(mutex_);
  error_ = std::move(error);
  closed_ = true;
  ready_.notify_one();
}

std::exception_ptr ReleaseQueue::error() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

bool ReleaseQueue::pop(ReleasedItem& out, bool& newer_frame) {
  std::unique_lock<std::mutex> lock(mutex_);
  ready_.wait(lock, [&] { return !items_.empty() || closed_; });
  if (items_.empty()) return false;
  out = std::move(items_.front());
  items_.pop_front();
  queued_events_ -= out.events.size();
  queued_frames_ -= out.frame;
  newer_frame = std::any_of(items_.begin(), items_.end(), [](const ReleasedItem& i) { return i.frame; });
  return true;
}

std::size_t ReleaseQueue::droppedEvents() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return dropped_events_;
}

std::size_t ReleaseQueue::droppedFrames() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return dropped_frames_;
}

}  // namespace eds
