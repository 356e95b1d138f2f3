#include "io/libcaer_payload.hpp"

#include <cstring>
#include <limits>

namespace eds {

void decodeLibcaer(const std::uint8_t* data, std::size_t bytes, TimeNs time_base, EventArray& out) {
  constexpr std::size_t kEventBytes = 8;
  if (bytes % kEventBytes != 0)
    throw PayloadError(bytes, "libcaer payload of " + std::to_string(bytes) + " bytes is not 8-byte events");
  const std::size_t n = bytes / kEventBytes, first = out.size();
  out.resize(first + n);
  TimeNs high = time_base;
  std::int32_t last_low = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t word;
    std::int32_t low;
    std::memcpy(&word, data + i * kEventBytes, 4);
    std::memcpy(&low, data + i * kEventBytes + 4, 4);
    if (low < 0)
      throw PayloadError(i * kEventBytes, "libcaer event " + std::to_string(i) + " has a negative time");
    if (i > 0 && low < last_low) {  // the 31-bit µs clock wrapped
      constexpr TimeNs kWrap = (TimeNs{1} << 31) * kNsPerUs;
      if (high > std::numeric_limits<TimeNs>::max() - 2 * kWrap)
        throw PayloadError(i * kEventBytes, "libcaer event " + std::to_string(i) + ": time beyond int64 ns");
      high += kWrap;
    }
    last_low = low;
    out.t[first + i] = high + static_cast<TimeNs>(low) * kNsPerUs;
    out.x[first + i] = static_cast<std::uint16_t>((word >> 17) & 0x7FFF);
    out.y[first + i] = static_cast<std::uint16_t>((word >> 2) & 0x7FFF);
    out.p[first + i] = (word >> 1) & 1 ? 1 : -1;
  }
}

void decodeLibcaerCompressed(const std::uint8_t* data, std::size_t bytes, TimeNs time_base, EventArray& out) {
  if (bytes % 2 != 0)
    throw PayloadError(bytes,
                       "libcaer_cmp payload of " + std::to_string(bytes) + " bytes is not 16-bit tokens");
  std::uint32_t time_high = 0, time_low = 0;
  std::uint16_t x = 0, base_y = 0;
  std::int8_t polarity = -1;
  const auto emit = [&](std::uint16_t y) {
    out.push_back(time_base + static_cast<TimeNs>(time_high | time_low) * kNsPerUs, x, y, polarity);
  };
  for (std::size_t b = 0; b < bytes; b += 2) {
    const auto token = static_cast<std::uint16_t>(data[b] | (data[b + 1] << 8));
    const std::uint16_t payload = token & 0x0FFF;
    switch (token >> 12) {
      case 0: time_high = static_cast<std::uint32_t>(payload) << 12; break;
      case 1: time_low = payload; break;
      case 2: x = payload & 0x07FF; break;
      case 3:
        polarity = payload & 0x0800 ? 1 : -1;
        emit(payload & 0x07FF);
        break;
      case 4:
        polarity = payload & 0x0800 ? 1 : -1;
        base_y = payload & 0x07FF;
        break;
      case 5:
        for (int i = 0; i < 8; ++i)
          if (payload & (1u << i)) emit(static_cast<std::uint16_t>(base_y + i));
        base_y = static_cast<std::uint16_t>(base_y + 8);
        break;
      default:
        throw PayloadError(b, "libcaer_cmp token " + std::to_string(b / 2) + " has unknown code " +
                                  std::to_string(token >> 12));
    }
  }
}

}  // namespace eds
