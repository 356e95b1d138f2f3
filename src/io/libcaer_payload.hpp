#pragma once
// event_camera_msgs/EventPacket payloads written by the libcaer ROS driver (iniVation DVS/DAVIS):
// - "libcaer": 8 bytes per event, little-endian: uint32 data (bit 1 polarity, bits 2-16 y, bits 17-31
//   x) and int32 timestamp, the low 31 bits of the sensor's µs clock. The time is
//   time_base (ns) + timestamp * 1000, plus 2^31 µs each time the timestamp falls back in a message.
// - "libcaer_cmp": 16-bit tokens, code in bits 12-15: 0 time high (bits 12-23 of the µs offset from
//   time_base), 1 time low (bits 0-11), 2 x (11 bits), 3 y (11 bits) + polarity (bit 11): one event,
//   4 base y + polarity, 5 an 8-bit mask of events at base y + i (base y then moves on by 8).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/events.hpp"

namespace eds {

// A payload that does not decode: what and at which byte.
struct PayloadError : std::runtime_error {
  PayloadError(std::size_t byte, const std::string& what) : std::runtime_error(what), byte(byte) {}
  std::size_t byte;
};

void decodeLibcaer(const std::uint8_t* data, std::size_t bytes, TimeNs time_base, EventArray& out);
void decodeLibcaerCompressed(const std::uint8_t* data, std::size_t bytes, TimeNs time_base, EventArray& out);

}  // namespace eds
