#pragma once
// Prophesee event streams: the EVT 2.0 (32-bit words) and EVT 3.0 (16-bit vectorized words) encodings,
// as written to `.raw` files by Metavision (a text header of `% key value` lines, then the words) and
// carried in ROS `event_camera_msgs/EventPacket` messages (encoding "evt3"); and the older `.dat` CD
// files (a `% ` header, a type and a size byte, then 8-byte records).
// Times are the sensor's microseconds, converted to ns; EVT 3.0's 24-bit time wraps every 16.8 s and
// is unwrapped here.
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/events.hpp"
#include "io/event_source.hpp"

namespace eds {

enum class EvtFormat { kEvt2, kEvt3, kDat };

// A word of a type the encoding does not define, at index `word` of the decoded block.
struct EvtWordError {
  std::size_t word;
  unsigned type;
};

// Decodes EVT 3.0 words; the state carries across calls, so a stream may be cut anywhere. Events are
// placed once a TIME_HIGH and then a TIME_LOW have been seen; those before carry no time and are dropped.
// Times come out as the sensor wrote them: nearly, not strictly, in order (steps back of a few µs).
// Throws EvtWordError on an undefined word type.
class Evt3Decoder {
 public:
  void decode(const std::uint16_t* words, std::size_t n, EventArray& cd, std::vector<TriggerEvent>& triggers);

 private:
  // Events are staged in fixed arrays and appended to the output in bulk: four vector push_backs per
  // event (each a capacity check) cost as much as the decoding itself.
  static constexpr std::size_t kStage = 2048;
  struct Stage {
    TimeNs t[kStage];
    std::uint16_t x[kStage], y[kStage];
    std::int8_t p[kStage];
    std::size_t n = 0;
  };
  void flush(EventArray& cd);
  void timeHigh(std::uint16_t w);
  void timeLow(std::uint16_t w);
  void updateNow() { now_ = static_cast<TimeNs>(((time_high_ << 12) | time_low_) * kNsPerUs); }
  Stage stage_;
  TimeNs now_ = 0;
  std::uint64_t time_high_ = 0;  // the time's bits 12..23, with the counter's wraps above them
  std::uint32_t time_low_ = 0;
  bool have_high_ = false, have_time_ = false, high_since_low_ = false;
  std::uint16_t y_ = 0, base_x_ = 0;
  std::int8_t vector_polarity_ = 1;
};

// Decodes EVT 2.0 words; words before the first TIME_HIGH are dropped. Throws EvtWordError.
class Evt2Decoder {
 public:
  void decode(const std::uint32_t* words, std::size_t n, EventArray& cd, std::vector<TriggerEvent>& triggers);

 private:
  std::uint64_t time_high_ = 0;  // the time's bits 6..33
  bool have_time_ = false;
};

// Decodes the 8-byte CD records of a Prophesee .dat file: uint32 time in µs (it wraps every 71.6 min and
// is unwrapped here), then uint32 x (bits 0-13), y (bits 14-27), polarity (bit 28).
class DatDecoder {
 public:
  void decode(const std::uint8_t* records, std::size_t n, EventArray& cd);

 private:
  std::uint64_t wraps_ = 0;
  std::uint32_t last_ = 0;
};

// Makes a nearly ordered stream ordered: a time a little before the latest one (the sensor's own
// disorder, a few µs) is raised to it; a step back of more than `tolerance_ns` is an error, as is a
// time that is not finite. Returns the index of the first event that steps back too far, or n.
class TimeOrder {
 public:
  explicit TimeOrder(TimeNs tolerance_ns = 1'000'000) : tolerance_ns_(tolerance_ns) {}
  std::size_t apply(EventArray& events, std::size_t from);
  TimeNs latest() const { return latest_; }
  std::uint64_t raised() const { return raised_; }  // how many times were raised so far

 private:
  TimeNs tolerance_ns_;
  TimeNs latest_ = std::numeric_limits<TimeNs>::min();
  std::uint64_t raised_ = 0;
};

struct PropheseeHeader {
  EvtFormat format = EvtFormat::kEvt3;
  int width = 0, height = 0;  // 0 when neither the header nor a known sensor gives them
  std::uint64_t data_offset = 0;
};

// Reads the `% ...` header of a .raw file; InputError naming the file if it has none or names an
// encoding other than EVT 2.0 / 3.0.
PropheseeHeader readPropheseeHeader(const std::filesystem::path& file);
// True when the file starts like a Metavision .raw file ("% " header line).

struct PropheseeOptions {
  int width = 0, height = 0;  // override the header's sensor size (required when it has none)
};

class PropheseeRawSource : public BlockEventSource {
 public:
  explicit PropheseeRawSource(const std::filesystem::path& file, PropheseeOptions options = {});
  ~PropheseeRawSource() override;

  const PropheseeHeader& header() const;
  // External trigger edges decoded so far (they come with the events, in time order).
  const std::vector<TriggerEvent>& triggers() const override;
  // Events so far whose time, slightly before an earlier event's, was raised to it (TimeOrder).
  std::uint64_t raisedTimes() const;

 private:
  bool decodeNextBlock(EventArray& block) override;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace eds
