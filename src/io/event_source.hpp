#pragma once
#include <algorithm>
#include <cstddef>
#include <optional>
#include <vector>

#include "core/events.hpp"

namespace eds {

// A stream of events in time order, read in chunks so that a long sequence never needs all its
// events in memory at once.
class EventSource {
 public:
  virtual ~EventSource() = default;
  // Appends up to max_events events to out (does not clear it); returns how many were appended,
  // 0 at the end of the stream. Throws InputError (file and line/index) on bad data.
  virtual std::size_t read(EventArray& out, std::size_t max_events) = 0;
  // Total number of events if known without reading everything (HDF5: yes; text: no).
  virtual std::optional<std::size_t> size() const { return std::nullopt; }
  // External trigger edges read so far, in time order (formats that record them beside the events).
  virtual const std::vector<TriggerEvent>& triggers() const { return no_triggers_; }

 private:
  std::vector<TriggerEvent> no_triggers_;
};

// A source that decodes its input a block at a time (a chunk of words, a message) and hands the events
// out in whatever amounts are asked for.
class BlockEventSource : public EventSource {
 public:
  std::size_t read(EventArray& out, std::size_t max_events) final {
    std::size_t appended = 0;
    while (appended < max_events) {
      if (pos_ == block_.size()) {
        block_.clear();
        pos_ = 0;
        if (!decodeNextBlock(block_)) break;
        continue;
      }
      const std::size_t n = std::min(max_events - appended, block_.size() - pos_);
      appendRange(out, block_, pos_, n);
      pos_ += n;
      appended += n;
    }
    return appended;
  }

 protected:
  // Decodes the next block into `block` (empty on entry); false at the end of the input. A block may
  // decode to no events (it is then skipped).
  virtual bool decodeNextBlock(EventArray& block) = 0;

 private:
  EventArray block_;
  std::size_t pos_ = 0;
};

}  // namespace eds
