#pragma once
// Packets of N events every `stride` events from a streaming source (event frames with overlap),
// keeping only a bounded window of events in memory.
#include <algorithm>
#include <cstddef>

#include "core/events.hpp"
#include "io/event_source.hpp"

namespace eds {

class EventPacketStream {
 public:
  EventPacketStream(EventSource& src, std::size_t n, std::size_t stride)
      : src_(src), n_(n), stride_(stride) {}
  bool next(const EventArray*& events, std::size_t& begin) {
    while (buf_.size() < pos_ + n_) {
      if (pos_ > (1u << 20)) compact();
      if (src_.read(buf_, 1 << 18) == 0) return false;
    }
    events = &buf_;
    begin = pos_;
    pos_ += stride_;
    return true;
  }

 private:
  void compact() {
    // Keeps N events before the next packet: the builder looks back at them (reversal_compensation).
    const auto d = static_cast<std::ptrdiff_t>(pos_ - std::min(pos_, n_));
    buf_.t.erase(buf_.t.begin(), buf_.t.begin() + d);
    buf_.x.erase(buf_.x.begin(), buf_.x.begin() + d);
    buf_.y.erase(buf_.y.begin(), buf_.y.begin() + d);
    buf_.p.erase(buf_.p.begin(), buf_.p.begin() + d);
    pos_ -= static_cast<std::size_t>(d);
  }
  EventSource& src_;
  std::size_t n_, stride_, pos_ = 0;
  EventArray buf_;
};

}  // namespace eds
