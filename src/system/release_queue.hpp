#pragma once
// The hand-over between a camera (a producer thread releasing events and frames on the wall clock)
// and the processing thread. A camera cannot wait, so a push never blocks; beyond its bounds the
// queue drops its oldest event chunks, or the frame whose loss leaves the shortest time between the
// frames kept (a backlog keeps frames spread over it), and counts what it dropped.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <mutex>
#include <opencv2/core.hpp>

#include "core/events.hpp"

namespace eds {

struct ReleasedItem {
  using Clock = std::chrono::steady_clock;
  bool frame = false;
  std::size_t index = 0;  // frames: into the sequence's frames
  TimeNs t = 0;           // frames: the frame's time
  cv::Mat image;
  EventArray events;  // event chunks
  Clock::time_point released;
};

class ReleaseQueue {
 public:
  ReleaseQueue(std::size_t max_events, std::size_t max_frames)
      : max_events_(max_events), max_frames_(max_frames) {}

  void push(ReleasedItem item);
  void close();
  // The producer failed (bad input in the recording): closes the queue; the consumer rethrows.
  void fail(std::exception_ptr error);
  std::exception_ptr error() const;

  // Waits for an item. False once closed and empty. `newer_frame`: a later frame is already waiting.
  bool pop(ReleasedItem& out, bool& newer_frame);

  std::size_t droppedEvents() const;
  std::size_t droppedFrames() const;

 private:
  void dropOldestChunk();  // under the lock
  void thinFrames();       // under the lock

  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<ReleasedItem> items_;
  std::size_t max_events_, queued_events_ = 0, dropped_events_ = 0;
  std::size_t max_frames_, queued_frames_ = 0, dropped_frames_ = 0;
  TimeNs last_frame_t_ = 0;  // the last frame popped (has_popped_frame_)
  bool has_popped_frame_ = false, closed_ = false;
  std::exception_ptr error_;
};

}  // namespace eds
