// ROS bags by content: ROS 1 bag v2.0, rosbag2 SQLite, MCAP; every message, the event topic decoded
// and the recording index (frames, CameraInfo, ground truth, IMU) built as `eds run` does.
#include "fuzz_input.hpp"
#include "io/ros_bag.hpp"
#include "io/ros_events.hpp"
#include "io/ros_recording.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = eds::fuzz::writeInput(data, size, "recording.bag");
  eds::fuzz::expectOnlyInputErrors([&] {
    auto bag = eds::openRosBag(file);
    eds::RosMessage m;
    while (bag->next(m)) {
    }
  });
  eds::fuzz::expectOnlyInputErrors([&] {
    eds::RosEventSource src(file);
    eds::EventArray out;
    while (src.read(out, 4096) > 0) out.clear();
  });
  eds::fuzz::expectOnlyInputErrors([&] {
    const eds::RosRecordingIndex idx = eds::indexRosRecording(file, {});
    if (!idx.frames.empty()) eds::RosFrameLoader(file).load(idx.frames.front().message);
  });
  return 0;
}
