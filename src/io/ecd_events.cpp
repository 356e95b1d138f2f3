#include "io/ecd_events.hpp"

#include <string>

#include "core/error.hpp"
#include "io/line_reader.hpp"
#include "io/text_parse.hpp"

namespace eds {

EcdEventSource::EcdEventSource(const std::filesystem::path& file, EcdEventOptions opts)
    : reader_(std::make_unique<LineReader>(file)), opts_(opts) {}

EcdEventSource::~EcdEventSource() = default;

std::size_t EcdEventSource::read(EventArray& out, std::size_t max_events) {
  const std::size_t base = out.size();
  // Grow once and write by index: four push_backs per event cost more than the parsing.
  out.resize(base + max_events);
  TimeNs* ts = out.t.data() + base;
  std::uint16_t* xs = out.x.data() + base;
  std::uint16_t* ys = out.y.data() + base;
  std::int8_t* ps = out.p.data() + base;
  std::size_t n = 0;
  std::string_view line;
  const auto fail = [&](const std::string& what) {
    out.resize(base + n);
    throw InputError(reader_->fileName(), reader_->lineNumber(),
                     what + " in '" + std::string(line.substr(0, 80)) + "'");
  };
  while (n < max_events && reader_->next(line)) {
    const char* p = line.data();
    const char* end = p + line.size();
    p = text::skipSpaces(p, end);
    if (p == end || *p == '#') continue;  // blank or comment line
    TimeNs t;
    std::int32_t x, y;
    const char* q = text::parseSecondsNs(p, end, t);
    if (!q || !text::atFieldEnd(q, end))
      fail(*p == '-' ? "negative timestamp" : "malformed timestamp");
    q = text::skipSpaces(q, end);
    const char* r = text::parseUint(q, end, x);
    if (!r || !text::atFieldEnd(r, end)) fail(q == end ? "missing x (expected 't x y p')" : "malformed x");
    q = text::skipSpaces(r, end);
    r = text::parseUint(q, end, y);
    if (!r || !text::atFieldEnd(r, end)) fail(q == end ? "missing y (expected 't x y p')" : "malformed y");
    q = text::skipSpaces(r, end);
    std::int8_t pol = 0;
    if (q < end && *q == '1') {
      pol = 1, ++q;
    } else if (q < end && *q == '0') {
      pol = -1, ++q;
    } else if (q + 1 < end && (*q == '-' || *q == '+') && q[1] == '1') {
      pol = *q == '-' ? -1 : 1, q += 2;
    } else {
      fail(q == end ? "missing polarity (expected 't x y p')" : "polarity must be 0/1 or -1/+1");
    }
    if (!text::atFieldEnd(q, end)) fail("polarity must be 0/1 or -1/+1");
    if (text::skipSpaces(q, end) != end) fail("more than 4 fields (expected 't x y p')");
    if ((opts_.width > 0 && x >= opts_.width) || (opts_.height > 0 && y >= opts_.height))
      fail("pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") outside the " +
           std::to_string(opts_.width) + "x" + std::to_string(opts_.height) + " sensor");
    if (x > 65535 || y > 65535) fail("pixel coordinate above 65535");
    if (t < last_t_) fail("timestamp decreases (events must be sorted by time)");
    last_t_ = t;
    ts[n] = t;
    xs[n] = static_cast<std::uint16_t>(x);
    ys[n] = static_cast<std::uint16_t>(y);
    ps[n] = pol;
    ++n;
  }
  out.resize(base + n);
  return n;
}

}  // namespace eds
