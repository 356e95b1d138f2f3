#pragma once
// Decoding the ROS messages eds reads, in both serializations: ROS 1 (packed, little-endian, strings
// without terminator) and ROS 2 CDR (a 4-byte encapsulation header, primitives aligned to their size,
// strings with a terminating NUL). The message layouts are fixed here, not parsed from definitions:
// a bag's type name and, for ROS 1, its md5sum say which layout a topic has.
#include <cstdint>
#include <string>

#include "core/time.hpp"
#include "io/binary_file.hpp"

namespace eds {

enum class RosSerialization { kRos1, kCdr };

class RosMessageReader {
 public:
  // InputError (naming the message's place) if a CDR message is big-endian or lacks its header.
  RosMessageReader(ByteView data, RosSerialization kind);

  std::uint8_t u8(const char* what) { return read<std::uint8_t>(what); }
  std::uint16_t u16(const char* what) { return read<std::uint16_t>(what); }
  std::uint32_t u32(const char* what) { return read<std::uint32_t>(what); }
  std::int32_t i32(const char* what) { return read<std::int32_t>(what); }
  std::uint64_t u64(const char* what) { return read<std::uint64_t>(what); }
  double f64(const char* what) { return read<double>(what); }
  std::string string(const char* what);
  // A uint8[] (length, then bytes): a view of the bytes.
  ByteView bytes(const char* what);
  // A sequence length (uint32), checked against the bytes left for `element_bytes` each.
  std::uint32_t sequenceLength(std::size_t element_bytes, const char* what);
  // builtin time: ROS 1 (uint32 sec, uint32 nsec), ROS 2 (int32 sec, uint32 nsec).
  TimeNs time(const char* what);
  // std_msgs/Header: stamp (and frame_id); ROS 1 has a uint32 seq first.
  TimeNs header(std::string* frame_id = nullptr);
  void align(std::size_t n);
  ByteView& view() { return v_; }
  InputError error(const std::string& what) const { return v_.error(v_.pos(), what); }

 private:
  template <typename T>
  T read(const char* what) {
    align(sizeof(T));
    return v_.le<T>(what);
  }
  ByteView v_;
  RosSerialization kind_;
  std::size_t origin_ = 0;  // CDR aligns relative to the byte after the encapsulation header
};

// event_camera_msgs/EventPacket.
struct EventPacketMsg {
  TimeNs stamp = 0;
  std::uint32_t width = 0, height = 0;
  std::uint64_t seq = 0, time_base = 0;
  std::string encoding;
  bool big_endian = false;
  ByteView events{nullptr, 0, nullptr, 0};
};
EventPacketMsg readEventPacket(RosMessageReader& r);

}  // namespace eds
