#pragma once
// Packets of N events every `stride` events from a streaming source (event frames with overlap),
// keeping only a bounded window of events in memory.
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "core/events.hpp"
#include "core/time.hpp"
#include "frontend/event_frame.hpp"
#include "io/event_source.hpp"

namespace eds {

// Removes the first n events of `events` (a moving window's consumed part).
inline void eraseFront(EventArray& events, std::size_t n) {
  const auto d = static_cast<std::ptrdiff_t>(n);
  events.t.erase(events.t.begin(), events.t.begin() + d);
  events.x.erase(events.x.begin(), events.x.begin() + d);
  events.y.erase(events.y.begin(), events.y.begin() + d);
  events.p.erase(events.p.begin(), events.p.begin() + d);
}

// Where each packet starts: `stride` events after the one before and, with a rate cap, no earlier
// than 1 / max_rate_hz after it (the events between are skipped). Decided on the events alone, so a
// stream gives the same packets whatever its chunks.
class PacketStarts {
 public:
  PacketStarts(std::size_t stride, double max_rate_hz)
      : stride_(stride), period_(max_rate_hz > 0 ? fromSeconds(1.0 / max_rate_hz) : 0) {}
  // After a packet at pos: the next start, before any skipping. With `every` > 1 the next every - 1
  // packets are passed over (not built): a consumer that falls behind.
  void advance(const EventArray& buf, std::size_t& pos, std::size_t every = 1) {
    t_min_ = buf.t[pos] + period_;
    pos += stride_ * every;
  }
  // Skips the events before the earliest time allowed; true when pos moved.
  bool skip(const EventArray& buf, std::size_t& pos) const {
    if (period_ == 0 || pos >= buf.size() || buf.t[pos] >= t_min_) return false;
    const auto first = buf.t.begin() + static_cast<std::ptrdiff_t>(pos);
    pos = static_cast<std::size_t>(std::lower_bound(first, buf.t.end(), t_min_) - buf.t.begin());
    return true;
  }

 private:
  std::size_t stride_;
  TimeNs period_;
  TimeNs t_min_ = 0;
};

class EventPacketStream {
 public:
  // `lookahead`: events after each packet that must be read too, where the stream has them (the
  // builder's EventFrameConfig::lookahead()).
  EventPacketStream(EventSource& src, std::size_t n, std::size_t stride, std::size_t lookahead = 0,
                    double max_rate_hz = 0)
      : src_(src), n_(n), lookahead_(lookahead), starts_(stride, max_rate_hz) {}
  // The packets an EventFrameBuilder with `cfg` builds its event frames from.
  EventPacketStream(EventSource& src, const EventFrameConfig& cfg)
      : EventPacketStream(src, static_cast<std::size_t>(cfg.num_events), cfg.stride(), cfg.lookahead(),
                          cfg.max_rate_hz) {}
  // The next packet: events [begin, begin + N) of *events. False at the end of the stream.
  bool next(const EventArray*& events, std::size_t& begin) {
    do {
      while (!exhausted_ && buf_.size() < pos_ + n_ + lookahead_) {
        if (pos_ > (1u << 20)) compact();
        if (src_.read(buf_, 1 << 18) == 0) exhausted_ = true;
      }
    } while (starts_.skip(buf_, pos_));
    if (buf_.size() < pos_ + n_) return false;
    events = &buf_;
    begin = pos_;
    starts_.advance(buf_, pos_);
    return true;
  }
  // Stream index of (*events)[0]: how many events were dropped before it.
  std::uint64_t base() const { return dropped_; }

 private:
  void compact() {
    // Drops everything before the next packet: the builder's per-pixel memory has already run past
    // it (up to the last packet's end and lookahead).
    eraseFront(buf_, pos_);
    dropped_ += pos_;
    pos_ = 0;
  }
  EventSource& src_;
  std::size_t n_, lookahead_, pos_ = 0;
  PacketStarts starts_;
  std::uint64_t dropped_ = 0;
  bool exhausted_ = false;
  EventArray buf_;
};

}  // namespace eds
