#include "system/event_frame_producer.hpp"

#include <algorithm>

namespace eds {

namespace {
// Events queued for the producer thread before add() waits: a few chunks, ~13 MB.
constexpr std::size_t kMaxQueuedEvents = std::size_t{1} << 20;
}  // namespace

EventFrameProducer::EventFrameProducer(const Undistorter& undistorter, const EventFrameConfig& cfg,
                                       const FlickerFilterConfig& flicker, bool threaded,
                                       StageClock* caller_clock)
    : builder_(undistorter, cfg),
      n_(static_cast<std::size_t>(cfg.num_events)),
      starts_(cfg.stride(), cfg.max_rate_hz),
      lookahead_(cfg.lookahead()),
      flicker_(undistorter.raw().width, undistorter.raw().height, flicker),
      threaded_(threaded),
      caller_clock_(caller_clock),
      clock_(threaded ? &thread_clock_ : caller_clock) {
  if (threaded_) thread_ = std::thread([this] { run(); });
}

EventFrameProducer::~EventFrameProducer() {
  if (!thread_.joinable()) return;
  {
    const std::lock_guard lk(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

std::size_t EventFrameProducer::need() const {
  return pos_ + n_ + lookahead_ > buf_.size() ? pos_ + n_ + lookahead_ - buf_.size() : 1;
}

void EventFrameProducer::add(const EventArray& ev, std::size_t begin, std::size_t end,
                             const std::function<void()>& built) {
  if (!threaded_) {
    for (std::size_t i = begin; i < end;) {
      const std::size_t k = std::min(end - i, need());
      step(ev, i, i + k);
      i += k;
      built();
    }
    return;
  }
  EventArray chunk;
  {
    const ScopedStage copy(caller_clock_, Stage::kEventIntake);
    appendRange(chunk, ev, begin, end - begin);
  }
  {
    std::unique_lock lk(mutex_);
    if (!in_.empty() && in_events_ + chunk.size() > kMaxQueuedEvents) {
      const ScopedStage wait(caller_clock_, Stage::kWaitingForEvents);
      cv_.wait(lk, [&] { return error_ || in_.empty() || in_events_ + chunk.size() <= kMaxQueuedEvents; });
    }
    if (error_) std::rethrow_exception(error_);
    in_events_ += chunk.size();
    in_.push_back(std::move(chunk));
  }
  cv_.notify_all();
  built();
}

void EventFrameProducer::step(const EventArray& ev, std::size_t a, std::size_t b) {
  append(ev, a, b);
  buildPackets(false);
}

void EventFrameProducer::append(const EventArray& ev, std::size_t a, std::size_t b) {
  const ScopedStage stage(clock_, Stage::kEventIntake);
  // Drops the events before the next packet: the builder's per-pixel memory has run past them. Packets
  // passed over may put that packet beyond the events received so far.
  if (pos_ > (1u << 20)) {
    const std::size_t n = std::min(pos_, buf_.size());
    eraseFront(buf_, n);
    base_ += n;
    pos_ -= n;
  }
  // Sized for all, then cut to those kept: no capacity check per event.
  std::size_t n = buf_.size();
  buf_.resize(n + (b - a));
  constexpr std::size_t kAhead = 16;  // events whose pixel state is fetched ahead
  for (std::size_t i = a; i < b; ++i) {
    if (i + kAhead < b) flicker_.prefetch(ev.x[i + kAhead], ev.y[i + kAhead]);
    if (!flicker_.keep(ev.t[i], ev.x[i], ev.y[i], ev.p[i])) continue;
    buf_.t[n] = ev.t[i], buf_.x[n] = ev.x[i], buf_.y[n] = ev.y[i], buf_.p[n] = ev.p[i];
    ++n;
  }
  buf_.resize(n);
  if (b > a) newest_appended_ = ev.t[b - 1];
}

// Every packet whose events (and lookahead) have arrived; at the end, every complete packet. Then
// what the consumer may see: the frames, and where the next packet starts.
void EventFrameProducer::buildPackets(bool at_end) {
  const ScopedStage stage(clock_, Stage::kEventFrames);
  for (;;) {
    starts_.skip(buf_, pos_);
    if (buf_.size() < pos_ + n_ + (at_end ? 0 : lookahead_)) break;
    EventFrame ef;
    {
      const std::lock_guard lk(mutex_);
      if (!spare_.empty()) {
        ef = std::move(spare_.back());
        spare_.pop_back();
      }
    }
    builder_.build(buf_, pos_, ef, base_);
    ef.passed_before = passed_last_;
    built_.push_back(std::move(ef));
    const std::size_t every = every_.load(std::memory_order_relaxed);
    starts_.advance(buf_, pos_, every);
    passing_ += every - 1;
    passed_last_ = every - 1;
  }
  {
    const std::lock_guard lk(mutex_);
    for (EventFrame& ef : built_) out_.push_back(std::move(ef));
    has_next_ = pos_ < buf_.size();
    if (has_next_) next_start_ = buf_.t[pos_];
    dropped_ = flicker_.dropped();
    passed_ = passing_;
    newest_ = newest_appended_;
  }
  if (threaded_ && !built_.empty()) cv_.notify_all();
  built_.clear();
}

void EventFrameProducer::run() {
  for (;;) {
    EventArray chunk;
    {
      std::unique_lock lk(mutex_);
      cv_.wait(lk, [&] { return stop_ || finishing_ || !in_.empty(); });
      if (stop_) return;
      if (in_.empty()) break;  // finishing, and everything queued is done
      chunk = std::move(in_.front());
      in_.pop_front();
      working_ = true;
    }
    try {
      for (std::size_t i = 0; i < chunk.size();) {
        const std::size_t k = std::min(chunk.size() - i, need());
        step(chunk, i, i + k);
        i += k;
      }
    } catch (...) {
      const std::lock_guard lk(mutex_);
      error_ = std::current_exception();
    }
    {
      const std::lock_guard lk(mutex_);
      in_events_ -= chunk.size();
      working_ = false;
    }
    cv_.notify_all();
    if (error_) return;
  }
  try {
    buildPackets(true);
  } catch (...) {
    const std::lock_guard lk(mutex_);
    error_ = std::current_exception();
  }
}

void EventFrameProducer::finish() {
  if (!threaded_) {
    buildPackets(true);
    return;
  }
  {
    const std::lock_guard lk(mutex_);
    finishing_ = true;
  }
  cv_.notify_all();
  {
    const ScopedStage wait(caller_clock_, Stage::kWaitingForEvents);
    thread_.join();
  }
  rethrow();
}

void EventFrameProducer::rethrow() const {
  const std::lock_guard lk(mutex_);
  if (error_) std::rethrow_exception(error_);
}

void EventFrameProducer::take(std::deque<EventFrame>& out) {
  const std::lock_guard lk(mutex_);
  if (error_) std::rethrow_exception(error_);
  for (EventFrame& ef : out_) out.push_back(std::move(ef));
  out_.clear();
}

void EventFrameProducer::drain(std::deque<EventFrame>& out) {
  if (threaded_) {
    const ScopedStage wait(caller_clock_, Stage::kWaitingForEvents);
    std::unique_lock lk(mutex_);
    cv_.wait(lk, [&] { return error_ || (in_.empty() && !working_); });
  }
  take(out);
}

bool EventFrameProducer::idle() const {
  const std::lock_guard lk(mutex_);
  return in_.empty() && !working_;
}

bool EventFrameProducer::nextPacketStartsAtOrAfter(TimeNs t) const {
  const std::lock_guard lk(mutex_);
  return has_next_ && next_start_ >= t;
}

void EventFrameProducer::recycle(EventFrame&& ef) {
  const std::lock_guard lk(mutex_);
  spare_.push_back(std::move(ef));
}

TimeNs EventFrameProducer::newestEvent() const {
  const std::lock_guard lk(mutex_);
  return newest_;
}

std::size_t EventFrameProducer::packetsPassed() const {
  const std::lock_guard lk(mutex_);
  return passed_;
}

std::size_t EventFrameProducer::flickerDropped() const {
  const std::lock_guard lk(mutex_);
  return dropped_;
}

}  // namespace eds
