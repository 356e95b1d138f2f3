#include "io/ros_message.hpp"

namespace eds {

RosMessageReader::RosMessageReader(ByteView data, RosSerialization kind) : v_(data), kind_(kind) {
  if (kind_ != RosSerialization::kCdr) return;
  const auto id = v_.le<std::uint16_t>("CDR encapsulation header");
  v_.skip(2);  // options
  // Representation identifiers: 0x0000 CDR big-endian, 0x0100 CDR little-endian (as bytes 00 01).
  if (id != 0x0100) throw v_.error(0, "not little-endian CDR (encapsulation id " + std::to_string(id) + ")");
  origin_ = v_.pos();
}

void RosMessageReader::align(std::size_t n) {
  if (kind_ != RosSerialization::kCdr || n <= 1) return;
  const std::size_t rel = v_.pos() - origin_;
  const std::size_t pad = (n - rel % n) % n;
  if (pad) v_.skip(std::min(pad, v_.remaining()));
}

std::string RosMessageReader::string(const char* what) {
  const std::uint32_t len = u32(what);
  const ByteView s = v_.take(len, what);
  auto n = static_cast<std::size_t>(len);
  if (kind_ == RosSerialization::kCdr) {
    if (n == 0 || s.data()[n - 1] != 0)
      throw v_.error(v_.pos() - len, std::string(what) + ": CDR string without its NUL");
    --n;
  }
  return std::string(reinterpret_cast<const char*>(s.data()), n);
}

ByteView RosMessageReader::bytes(const char* what) { return v_.take(sequenceLength(1, what), what); }

std::uint32_t RosMessageReader::sequenceLength(std::size_t element_bytes, const char* what) {
  const std::uint32_t n = u32(what);
  if (element_bytes > 0 && static_cast<std::uint64_t>(n) * element_bytes > v_.remaining())
    throw v_.error(
        v_.pos(), std::string(what) + ": " + std::to_string(n) + " elements run past the end of the message");
  return n;
}

TimeNs RosMessageReader::time(const char* what) {
  const std::int64_t sec =
      kind_ == RosSerialization::kRos1 ? static_cast<std::int64_t>(u32(what)) : i32(what);
  const std::uint32_t nsec = u32(what);
  if (nsec >= 1'000'000'000u) throw v_.error(v_.pos() - 4, std::string(what) + ": nanoseconds out of range");
  return sec * kNsPerSec + nsec;
}

TimeNs RosMessageReader::header(std::string* frame_id) {
  if (kind_ == RosSerialization::kRos1) u32("header.seq");
  const TimeNs stamp = time("header.stamp");
  std::string id = string("header.frame_id");
  if (frame_id) *frame_id = std::move(id);
  return stamp;
}

EventPacketMsg readEventPacket(RosMessageReader& r) {
  EventPacketMsg m;
  m.stamp = r.header();
  m.height = r.u32("height");
  m.width = r.u32("width");
  m.seq = r.u64("seq");
  m.time_base = r.u64("time_base");
  m.encoding = r.string("encoding");
  m.big_endian = r.u8("is_bigendian") != 0;
  m.events = r.bytes("events");
  return m;
}

}  // namespace eds
