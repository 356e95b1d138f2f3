#include "system/release_queue.hpp"

#include <algorithm>
#include <limits>

namespace eds {

void ReleaseQueue::push(ReleasedItem item) {
  const std::lock_guard<std::mutex> lock(mutex_);
  queued_events_ += item.events.size();
  queued_frames_ += item.frame;
  items_.push_back(std::move(item));
  while (queued_events_ > max_events_) dropOldestChunk();  // the chunks hold all queued events
  while (queued_frames_ > max_frames_) thinFrames();
  ready_.notify_one();
}

void ReleaseQueue::dropOldestChunk() {
  const auto it = std::find_if(items_.begin(), items_.end(), [](const ReleasedItem& i) { return !i.frame; });
  queued_events_ -= it->events.size();
  dropped_events_ += it->events.size();
  items_.erase(it);
}

// Drops the frame, never the newest, whose neighbours are closest in time: the earliest of equals. The
// oldest queued frame's neighbour before it is the last popped; before any, it is kept (the start)
// unless only two frames are queued.
void ReleaseQueue::thinFrames() {
  auto best = items_.end();
  TimeNs best_gap = std::numeric_limits<TimeNs>::max();
  auto prev = items_.end(), cur = items_.end();
  for (auto it = items_.begin(); it != items_.end(); ++it) {
    if (!it->frame) continue;
    if (cur != items_.end() && (prev != items_.end() || has_popped_frame_)) {
      const TimeNs gap = it->t - (prev != items_.end() ? prev->t : last_frame_t_);
      if (gap < best_gap) best_gap = gap, best = cur;
    }
    prev = cur, cur = it;
  }
  if (best == items_.end())  // two frames and none popped: the older goes
    best = std::find_if(items_.begin(), items_.end(), [](const ReleasedItem& i) { return i.frame; });
  --queued_frames_, ++dropped_frames_;
  items_.erase(best);
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
  if (out.frame) last_frame_t_ = out.t, has_popped_frame_ = true;
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
