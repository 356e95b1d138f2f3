#pragma once
// Events in HDF5 files with the DSEC / EDS-dataset layout:
//   events/x, events/y (pixel), events/t (microseconds, relative to t_offset), events/p (0/1),
//   optional ms_to_idx (ms_to_idx[i] = first event with t >= i ms) and t_offset (µs, scalar).
// eds's own layout (eds_hdf5.hpp) is the same with t in nanoseconds.
// Any integer storage type is accepted for each field; HDF5 converts to the memory type and a value
// that does not fit is reported instead of being clipped silently.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/events.hpp"
#include "core/time.hpp"
#include "io/event_source.hpp"

namespace eds {

struct Hdf5EventOptions {
  // Sensor size; when > 0 every pixel is checked against it (0 disables the check).
  int width = 0;
  int height = 0;
  // Where the x, y, t, p datasets and the millisecond index are: DSEC and TUM-VIE "events" and
  // "ms_to_idx"; M3ED "prophesee/left" and "prophesee/left/ms_map_idx".
  std::string group = "events";
  std::string ms_index = "ms_to_idx";
  // Nanoseconds per unit of t (and t_offset): 1000 for µs (DSEC, TUM-VIE, M3ED), 1 for ns (eds's own
  // layout, which keeps simulated and converted times exactly). 1, 10, 100, 1000...
  std::int64_t tick_ns = 1000;
  // Trigger edges recorded beside the events (eds's layout keeps them in a dataset of their own).
  std::vector<TriggerEvent> triggers;
};

class Hdf5EventSource : public EventSource {
 public:
  // Opens and validates the layout (datasets present, 1-D, integer, equal non-zero lengths). The
  // values themselves are validated as they are read. Throws InputError naming the file.
  explicit Hdf5EventSource(const std::string& path, Hdf5EventOptions options = {});
  ~Hdf5EventSource() override;
  Hdf5EventSource(const Hdf5EventSource&) = delete;
  Hdf5EventSource& operator=(const Hdf5EventSource&) = delete;

  std::size_t read(EventArray& out, std::size_t max_events) override;
  std::optional<std::size_t> size() const override;
  const std::vector<TriggerEvent>& triggers() const override;

  // Positions the stream at the first event with t >= t_ns (the end if there is none). With
  // ms_to_idx the search is narrowed to one millisecond; without it, a binary search over events/t.
  void seek(TimeNs t_ns);
  // Positions the stream at an event index (clamped to size()).
  void seekIndex(std::size_t index);
  std::size_t position() const;

  TimeNs tOffsetNs() const;
  bool hasMsToIdx() const;
  TimeNs firstTimeNs() const;  // time of event 0
  TimeNs lastTimeNs() const;   // time of the last event
  const std::string& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

enum class Hdf5Compression { kNone, kGzip, kBloscIfAvailable };

// Writes the DSEC layout (x, y: uint16, t: int64 µs relative to t_offset_us, p: uint8 0/1,
// ms_to_idx: uint64, t_offset: int64 scalar). Times are stored in whole microseconds (floor).
// kBloscIfAvailable falls back to gzip when the blosc plugin cannot be loaded. Returns the
// compression actually used. Throws InputError naming the file on failure.
Hdf5Compression writeHdf5Events(const std::string& path, const EventArray& events, std::int64_t t_offset_us,
                                Hdf5Compression compression = Hdf5Compression::kNone);

// True when HDF5 can load the blosc filter (after adding the Debian plugin directory).
bool hdf5BloscAvailable();

}  // namespace eds
