#pragma once
// The event side of the odometry's stream merge: flicker filtering, buffering, and building event
// frames from packets whose starts are decided on the events alone. With `threaded`, this runs on a
// thread of its own beside the tracking (a pipeline with a bounded input queue): the frames it builds
// are the same as without, and the consumer asks for all queued work to be done (drain) before any
// decision that depends on what has not been built yet, so the results do not change either.
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <limits>
#include <mutex>
#include <thread>
#include <vector>

#include "core/events.hpp"
#include "core/time.hpp"
#include "frontend/event_frame.hpp"
#include "frontend/event_packets.hpp"
#include "frontend/flicker_filter.hpp"
#include "system/stage_clock.hpp"

namespace eds {

class EventFrameProducer {
 public:
  // `caller_clock`: the consuming thread's clock (charged with the work without a thread, with the
  // waits with one).
  EventFrameProducer(const Undistorter& undistorter, const EventFrameConfig& cfg,
                     const FlickerFilterConfig& flicker, bool threaded, StageClock* caller_clock);
  ~EventFrameProducer();
  EventFrameProducer(const EventFrameProducer&) = delete;
  EventFrameProducer& operator=(const EventFrameProducer&) = delete;

  // Events checked by the caller (time order, on the sensor). Without a thread they are appended in
  // steps of at most one packet and `built` runs after each step, so that every packet is used as soon
  // as it exists whatever the chunk size; with one, a copy is queued (waiting while the queue is full)
  // and `built` runs once.
  void add(const EventArray& ev, std::size_t begin, std::size_t end, const std::function<void()>& built);
  // No more events: the last complete packets are built (waits for the thread).
  void finish();
  // Moves the event frames built so far to the end of `out`, in time order.
  void take(std::deque<EventFrame>& out);
  // Waits until every queued event has been processed (at once without a thread), taking what was
  // built meanwhile into `out`.
  void drain(std::deque<EventFrame>& out);
  // Whether all queued events have been processed (always without a thread).
  bool idle() const;
  // Whether the next packet to be built (as far as the events processed so far tell) starts at or
  // after t: then no event frame still to come is earlier than t.
  bool nextPacketStartsAtOrAfter(TimeNs t) const;
  // From the next packet on, only every k-th packet is built (k >= 1; any thread): load shedding that
  // costs nothing for the packets passed over.
  void setEvery(std::size_t k) { every_.store(k, std::memory_order_relaxed); }
  // Packets passed over so far (setEvery).
  std::size_t packetsPassed() const;
  // A processed event frame's image back for reuse.
  void recycle(EventFrame&& ef);
  std::size_t flickerDropped() const;
  // The newest event processed (added, without a thread).
  TimeNs newestEvent() const;
  bool threaded() const { return threaded_; }
  // After finish(): the producer thread's time by stage (zeros without one).
  StageSeconds threadStageSeconds() { return thread_clock_.seconds(); }

 private:
  void step(const EventArray& ev, std::size_t a, std::size_t b);  // append, then build what is ready
  void append(const EventArray& ev, std::size_t a, std::size_t b);
  void buildPackets(bool at_end);
  std::size_t need() const;
  void run();
  void rethrow() const;

  EventFrameBuilder builder_;
  std::size_t n_;
  PacketStarts starts_;
  std::size_t lookahead_;
  FlickerFilter flicker_;  // in front of buf_: flickering pixels' events never enter it
  // Events not yet in a packet (from pos_ on) and the packets' lookahead; base_: stream index of buf_[0].
  EventArray buf_;
  std::size_t pos_ = 0;
  std::uint64_t base_ = 0;
  std::vector<EventFrame> built_;  // this step's frames, before they are published
  std::atomic<std::size_t> every_{1};
  std::size_t passing_ = 0;      // packets passed over (the working thread's count)
  std::size_t passed_last_ = 0;  // of them, those right after the last packet built
  TimeNs newest_appended_ = std::numeric_limits<TimeNs>::min();

  bool threaded_;
  StageClock* caller_clock_;
  StageClock* clock_;                      // the clock of the thread that does the work
  StageClock thread_clock_{Stage::kIdle};  // the producer thread's, read after it stopped
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  // Guarded by mutex_ (with a thread):
  std::deque<EventArray> in_;
  std::size_t in_events_ = 0;
  bool working_ = false, finishing_ = false, stop_ = false;
  std::deque<EventFrame> out_;
  std::vector<EventFrame> spare_;
  bool has_next_ = false;  // buf_ holds the next packet's first event, at next_start_
  TimeNs next_start_ = 0;
  TimeNs newest_ = std::numeric_limits<TimeNs>::min();
  std::size_t dropped_ = 0, passed_ = 0;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace eds
