#pragma once
// Hands out a sequence's events and frames merged in time order, streaming: events come in chunks
// that never pass the next frame's timestamp (events at exactly the frame time come first).
#include <cstddef>
#include <memory>

#include "io/sequence.hpp"

namespace eds {

class MergedStream {
 public:
  enum class Kind { kEvents, kFrame, kEnd };

  // with_events = false: the frames alone (the events are not read).
  explicit MergedStream(const Sequence& seq, std::size_t max_chunk = 50'000, bool with_events = true);

  // kEvents: `events` is cleared and filled with the next chunk (time-ordered, all <= next frame).
  // kFrame: `frame_index` is the index into seq.frames() of the next frame.
  Kind next(EventArray& events, std::size_t& frame_index);

 private:
  bool fillPending();  // false when the event source is exhausted

  const Sequence& seq_;
  std::unique_ptr<EventSource> source_;
  std::size_t max_chunk_;
  EventArray pending_;
  std::size_t pending_pos_ = 0;
  std::size_t next_frame_ = 0;
};

}  // namespace eds
