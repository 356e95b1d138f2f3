#pragma once
#include <cstddef>
#include <optional>

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
};

}  // namespace eds
