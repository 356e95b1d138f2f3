#pragma once
// Packets of N events every `stride` events from a streaming source (event frames with overlap),
// keeping only a bounded window of events in memory.
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "core/events.hpp"
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

class EventPacketStream {
 public:
  // `lookahead`: events after each packet that must be read too, where the stream has them (the
  // builder's EventFrameConfig::lookahead()).
  EventPacketStream(EventSource& src, std::size_t n, std::size_t stride, std::size_t lookahead = 0)
      : src_(src), n_(n), stride_(stride), lookahead_(lookahead) {}
  // The next packet: events [begin, begin + N) of *events. False at the end of the stream.
  bool next(const EventArray*& events, std::size_t& begin) {
    while (!exhausted_ && buf_.size() < pos_ + n_ + lookahead_) {
      if (pos_ > (1u << 20)) compact();
      if (src_.read(buf_, 1 << 18) == 0) exhausted_ = true;
    }
    if (buf_.size() < pos_ + n_) return false;
    events = &buf_;
    begin = pos_;
    pos_ += stride_;
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
  std::size_t n_, stride_, lookahead_, pos_ = 0;
  std::uint64_t dropped_ = 0;
  bool exhausted_ = false;
  EventArray buf_;
};

}  // namespace eds
