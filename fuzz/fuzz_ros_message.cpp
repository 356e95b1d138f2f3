// ROS messages in both serializations, straight from memory: the first byte picks the serialization
// and the message type (Image, CameraInfo, EventPacket).
#include "fuzz_input.hpp"
#include "io/ros_message.hpp"
#include "io/ros_recording.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const std::string name = "message";
  const auto kind = (data[0] & 1) ? eds::RosSerialization::kCdr : eds::RosSerialization::kRos1;
  const int type = (data[0] >> 1) % 3;
  eds::fuzz::expectOnlyInputErrors([&] {
    eds::RosMessageReader r(eds::ByteView(data + 1, size - 1, &name, 0), kind);
    if (type == 0) eds::decodeRosImage(r);
    if (type == 1) eds::decodeCameraInfo(r);
    if (type == 2) eds::readEventPacket(r);
  });
  return 0;
}
