#include "io/prophesee.hpp"

#include <algorithm>
#include <cstring>
#include <sstream>

#include "io/binary_file.hpp"

namespace eds {

namespace {

constexpr std::uint64_t kEvt3HighRange = 1u << 12;  // TIME_HIGH counts 12 bits, then wraps

// Sensor sizes of the Metavision plugins whose headers give none.
struct KnownSensor {
  const char* name_part;
  int width, height;
};
constexpr KnownSensor kKnownSensors[] = {{"gen41", 1280, 720}, {"imx636", 1280, 720}, {"gen31", 640, 480},
                                         {"gen3", 640, 480},   {"imx646", 1280, 720}, {"imx8", 320, 320}};

}  // namespace

std::size_t TimeOrder::apply(EventArray& events, std::size_t from) {
  for (std::size_t i = from; i < events.size(); ++i) {
    TimeNs& t = events.t[i];
    if (t >= latest_) {
      latest_ = t;
    } else if (latest_ - t <= tolerance_ns_) {
      t = latest_;
      ++raised_;
    } else {
      return i;
    }
  }
  return events.size();
}

void Evt3Decoder::timeHigh(std::uint16_t w) {
  const std::uint64_t high = w & 0xFFF;
  std::uint64_t full = (time_high_ & ~(kEvt3HighRange - 1)) | high;
  // Far below the last value: the 24-bit counter wrapped. A little below: the sensor's own disorder,
  // kept as it is (the reader that needs order deals with it).
  if (have_high_ && full + kEvt3HighRange / 2 < time_high_) full += kEvt3HighRange;
  time_high_ = full;
  have_high_ = true;
  high_since_low_ = true;
  updateNow();
}

void Evt3Decoder::timeLow(std::uint16_t w) {
  const std::uint32_t low = w & 0xFFF;
  // The low counter can wrap a few words before the TIME_HIGH that says so arrives; a drop of more
  // than half its range with no TIME_HIGH in between is that wrap (small drops are disorder, kept).
  if (have_time_ && !high_since_low_ && low + 2048 < time_low_) time_high_ += 1;
  time_low_ = low;
  high_since_low_ = false;
  have_time_ = have_high_;
  updateNow();
}

void Evt3Decoder::flush(EventArray& cd) {
  const std::size_t n = stage_.n;
  cd.t.insert(cd.t.end(), stage_.t, stage_.t + n);
  cd.x.insert(cd.x.end(), stage_.x, stage_.x + n);
  cd.y.insert(cd.y.end(), stage_.y, stage_.y + n);
  cd.p.insert(cd.p.end(), stage_.p, stage_.p + n);
  stage_.n = 0;
}

void Evt3Decoder::decode(const std::uint16_t* words, std::size_t n, EventArray& cd,
                         std::vector<TriggerEvent>& triggers) {
  cd.reserve(cd.size() + n);  // about one event per word: the vectors grow once, not per event
  // The state lives in locals while decoding: stores to the int8 polarities may alias any member, so
  // the compiler would reload members after each event.
  Stage& s = stage_;
  std::size_t k = s.n;
  std::uint16_t y = y_, base_x = base_x_;
  std::int8_t vector_polarity = vector_polarity_;
  TimeNs now = now_;
  const auto emit = [&](std::uint16_t x, std::int8_t p) {
    s.t[k] = now;
    s.x[k] = x;
    s.y[k] = y;
    s.p[k] = p;
    ++k;
  };
  const auto save = [&] {
    s.n = k;
    y_ = y, base_x_ = base_x, vector_polarity_ = vector_polarity;
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (k + 12 > kStage) {
      s.n = k;
      flush(cd);
      k = 0;
    }
    const std::uint16_t w = words[i];
    const unsigned type = w >> 12;
    if (type == 0x8 || type == 0x6) {  // TIME_HIGH, TIME_LOW
      type == 0x8 ? timeHigh(w) : timeLow(w);
      now = now_;
      continue;
    }
    if (!have_time_) continue;  // no time yet: nothing can be placed
    switch (type) {
      case 0x0: y = w & 0x7FF; break;                          // ADDR_Y
      case 0x2: emit(w & 0x7FF, (w & 0x800) ? 1 : -1); break;  // ADDR_X: one event
      case 0x3:                                                // VECT_BASE_X
        base_x = w & 0x7FF;
        vector_polarity = (w & 0x800) ? 1 : -1;
        break;
      case 0x4:    // VECT_12: an event at base_x + b for each set bit b
      case 0x5: {  // VECT_8
        const unsigned bits = type == 0x4 ? 12 : 8;
        for (unsigned m = w & ((1u << bits) - 1); m != 0; m &= m - 1)
          emit(static_cast<std::uint16_t>(base_x + __builtin_ctz(m)), vector_polarity);
        base_x = static_cast<std::uint16_t>(base_x + bits);
        break;
      }
      case 0xA: triggers.push_back({now, static_cast<std::uint8_t>((w >> 8) & 0xF), (w & 1) != 0}); break;
      case 0x7:
      case 0xE:
      case 0xF: break;  // CONTINUED_4, OTHERS, CONTINUED_12: no CD data
      default:
        save();
        flush(cd);  // the events before the bad word stay decoded
        throw EvtWordError{i, type};
    }
  }
  save();
  flush(cd);
}

void Evt2Decoder::decode(const std::uint32_t* words, std::size_t n, EventArray& cd,
                         std::vector<TriggerEvent>& triggers) {
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t w = words[i];
    const unsigned type = w >> 28;
    if (type == 0x8) {  // TIME_HIGH: the time's upper 28 bits
      time_high_ = w & 0x0FFFFFFF;
      have_time_ = true;
      continue;
    }
    if (!have_time_) continue;
    const auto t = static_cast<TimeNs>(((time_high_ << 6) | ((w >> 22) & 0x3F)) * kNsPerUs);
    if (type == 0x0 || type == 0x1) {  // CD_OFF, CD_ON
      cd.push_back(t, static_cast<std::uint16_t>((w >> 11) & 0x7FF), static_cast<std::uint16_t>(w & 0x7FF),
                   type == 0x1 ? 1 : -1);
    } else if (type == 0xA) {
      triggers.push_back({t, static_cast<std::uint8_t>((w >> 8) & 0x1F), (w & 1) != 0});
    } else if (type != 0xE && type != 0xF) {
      throw EvtWordError{i, type};
    }
  }
}

void DatDecoder::decode(const std::uint8_t* records, std::size_t n, EventArray& cd) {
  const std::size_t first = cd.size();
  cd.resize(first + n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t r[2];
    std::memcpy(r, records + 8 * i, 8);
    if (r[0] + (std::uint64_t{1} << 31) < last_) ++wraps_;  // far below the last time: the counter wrapped
    last_ = r[0];
    cd.t[first + i] = static_cast<TimeNs>(((wraps_ << 32) | r[0]) * kNsPerUs);
    cd.x[first + i] = static_cast<std::uint16_t>(r[1] & 0x3FFF);
    cd.y[first + i] = static_cast<std::uint16_t>((r[1] >> 14) & 0x3FFF);
    cd.p[first + i] = (r[1] >> 28) & 1 ? 1 : -1;
  }
}

namespace {

// "EVT3;height=720;width=1280" (the `format` key of newer headers).
void parseFormatKey(const std::string& value, PropheseeHeader& h, bool& have_format) {
  std::stringstream ss(value);
  for (std::string part; std::getline(ss, part, ';');) {
    if (part == "EVT3" || part == "EVT2") {
      h.format = part == "EVT3" ? EvtFormat::kEvt3 : EvtFormat::kEvt2;
      have_format = true;
    } else if (part.rfind("width=", 0) == 0) {
      h.width = std::atoi(part.c_str() + 6);
    } else if (part.rfind("height=", 0) == 0) {
      h.height = std::atoi(part.c_str() + 7);
    }
  }
}

// After a .dat header: the event type (0: 2D, 12: CD) and the record size, which must be 8.
void readDatTypeAndSize(BinaryFile& in, PropheseeHeader& h) {
  const std::uint64_t at = in.offset();
  std::uint8_t type_size[2];
  in.readExact(type_size, 2, ".dat event type and size");
  if ((type_size[0] != 0 && type_size[0] != 12) || type_size[1] != 8)
    throw errorAt(in.path(), at,
                  ".dat event type " + std::to_string(type_size[0]) + " of " + std::to_string(type_size[1]) +
                      " bytes is not read (CD events, type 0 or 12, of 8 bytes are)");
  h.format = EvtFormat::kDat;
}

}  // namespace

PropheseeHeader readPropheseeHeader(const std::filesystem::path& file) {
  BinaryFile in(file);
  PropheseeHeader h;
  bool have_format = false, dat_header = false;
  std::string line, plugin;
  std::size_t line_no = 0;
  while (!in.atEnd()) {
    const std::uint64_t start = in.offset();
    char c = 0;
    in.readExact(&c, 1, "header");
    in.seek(start);
    if (c != '%') break;
    in.readLine(line, 4096);
    ++line_no;
    if (line == "% end") break;
    if (line.size() < 2) continue;  // a bare '%'
    const std::size_t sp = line.find(' ', 2);
    const std::string key = line.substr(2, sp == std::string::npos ? std::string::npos : sp - 2);
    const std::string value = sp == std::string::npos ? "" : line.substr(sp + 1);
    if (key == "evt") {
      if (value != "2.0" && value != "3.0")
        throw InputError(file.string(), line_no,
                         "unsupported event encoding 'evt " + value + "' (EVT 2.0 and 3.0 are read)");
      h.format = value == "3.0" ? EvtFormat::kEvt3 : EvtFormat::kEvt2;
      have_format = true;
    } else if (key == "format") {
      parseFormatKey(value, h, have_format);
    } else if (key == "geometry") {
      std::sscanf(value.c_str(), "%dx%d", &h.width, &h.height);
    } else if (key == "plugin_name") {
      plugin = value;
    } else if (key == "Height" || key == "Width") {  // .dat headers
      (key == "Height" ? h.height : h.width) = std::atoi(value.c_str());
      dat_header = true;
    }
  }
  if (line_no == 0) throw InputError(file.string(), "not a Prophesee .raw file (no '% ' header)");
  if (!have_format && dat_header) readDatTypeAndSize(in, h);
  if (!have_format && !dat_header)
    throw InputError(file.string(), "header names no event encoding ('% evt 3.0' or '% format EVT3')");
  if (h.width <= 0 || h.height <= 0) {
    h.width = h.height = 0;
    for (const auto& s : kKnownSensors)
      if (plugin.find(s.name_part) != std::string::npos) {
        h.width = s.width;
        h.height = s.height;
        break;
      }
  }
  h.data_offset = in.offset();
  return h;
}

struct PropheseeRawSource::Impl {
  BinaryFile file;
  PropheseeHeader header;
  Evt2Decoder evt2;
  Evt3Decoder evt3;
  DatDecoder dat;
  std::vector<std::uint8_t> block;
  std::vector<TriggerEvent> triggers;
  TimeOrder order;
  std::uint64_t events_before = 0;  // events in the blocks before `pending`

  Impl(const std::filesystem::path& path, const PropheseeOptions& o)
      : file(path), header(readPropheseeHeader(path)) {
    if (o.width > 0) header.width = o.width;
    if (o.height > 0) header.height = o.height;
    file.seek(header.data_offset);
  }

  // Decodes the next block of words into `pending`; false at the end of the file.
  bool refill(EventArray& pending) {
    constexpr std::size_t kBlockBytes = 1 << 20;
    const std::size_t word = header.format == EvtFormat::kEvt3 ? 2 : header.format == EvtFormat::kDat ? 8 : 4;
    const std::uint64_t offset = file.offset();
    block.resize(kBlockBytes);
    const std::size_t read = file.readSome(block.data(), kBlockBytes);
    const std::size_t got = read / word * word;
    if (got == 0 && read > 0) throw errorAt(file.path(), offset, "truncated: the file ends inside a word");
    if (got == 0) return false;
    file.seek(offset + got);  // a partial trailing word is left for the next block (or dropped at the end)
    try {
      if (header.format == EvtFormat::kDat)
        dat.decode(block.data(), got / 8, pending);
      else if (header.format == EvtFormat::kEvt3)
        evt3.decode(reinterpret_cast<const std::uint16_t*>(block.data()), got / 2, pending, triggers);
      else
        evt2.decode(reinterpret_cast<const std::uint32_t*>(block.data()), got / 4, pending, triggers);
    } catch (const EvtWordError& e) {
      throw errorAt(file.path(), offset + e.word * word,
                    "word of undefined type " + std::to_string(e.type) + " (not " +
                        (header.format == EvtFormat::kEvt3 ? "EVT 3.0" : "EVT 2.0") + " data?)");
    }
    checkOrder(pending, offset);
    checkPixels(pending, offset);
    events_before += pending.size();
    return true;
  }

  void checkOrder(EventArray& pending, std::uint64_t block_offset) {
    const TimeNs latest = order.latest();
    const std::size_t bad = order.apply(pending, 0);
    if (bad == pending.size()) return;
    throw errorAt(file.path(), block_offset,
                  "events out of order: event " + std::to_string(events_before + bad) + " at " +
                      std::to_string(pending.t[bad] / kNsPerUs) + " us comes after one at " +
                      std::to_string(std::max(latest, bad > 0 ? pending.t[bad - 1] : latest) / kNsPerUs) +
                      " us (in the block of words from this offset)");
  }

  void checkPixels(const EventArray& pending, std::uint64_t block_offset) const {
    if (header.width <= 0) return;
    for (std::size_t i = 0; i < pending.size(); ++i)
      if (pending.x[i] >= header.width || pending.y[i] >= header.height)
        throw errorAt(file.path(), block_offset,
                      "event at pixel (" + std::to_string(pending.x[i]) + ", " +
                          std::to_string(pending.y[i]) + ") outside the " + std::to_string(header.width) +
                          "x" + std::to_string(header.height) +
                          " sensor (in the block of words from this offset; --resolution sets the size)");
  }
};

PropheseeRawSource::PropheseeRawSource(const std::filesystem::path& file, PropheseeOptions options)
    : impl_(std::make_unique<Impl>(file, options)) {}
PropheseeRawSource::~PropheseeRawSource() = default;

const PropheseeHeader& PropheseeRawSource::header() const { return impl_->header; }
const std::vector<TriggerEvent>& PropheseeRawSource::triggers() const { return impl_->triggers; }
std::uint64_t PropheseeRawSource::raisedTimes() const { return impl_->order.raised(); }

bool PropheseeRawSource::decodeNextBlock(EventArray& block) { return impl_->refill(block); }

}  // namespace eds
