#pragma once
// Events from a recorded ROS topic: dvs_msgs/EventArray (and prophesee_event_msgs/EventArray, the same
// layout) or event_camera_msgs/EventPacket with evt3 payloads, from any container openRosBag reads.
//
// Times: EventArray events carry ROS times. EventPacket events carry the sensor's clock; they are put
// on the recording's clock by one offset, the first packet's header stamp minus its first event's
// sensor time (the two clocks drift by parts per million: microseconds over a minute).
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "io/event_source.hpp"
#include "io/ros_bag.hpp"

namespace eds {

// Message types that carry events.
bool isEventTopicType(const std::string& type);
// The topic to read events from: `wanted` if given (InputError if the bag lacks it or it holds no
// events), else the only event topic (InputError listing them when there are several, or none).
std::size_t chooseEventTopic(const RosBagReader& bag, const std::string& wanted);

struct RosEventStats {
  std::uint64_t messages = 0;
  std::uint32_t width = 0, height = 0;  // from the last message
  std::vector<TriggerEvent> triggers;   // external trigger edges (EventPacket evt3)
  TimeNs sensor_offset = 0;             // recording clock minus sensor clock (EventPacket)
  std::uint64_t raised = 0;             // events whose slightly early time was raised to keep order
};

class RosEventSource : public BlockEventSource {
 public:
  // `topic` empty picks the event topic by type.
  explicit RosEventSource(const std::filesystem::path& path, const std::string& topic = "");
  ~RosEventSource() override;
  const RosTopic& topic() const;
  const char* bagFormat() const;
  const RosEventStats& stats() const;
  const std::vector<TriggerEvent>& triggers() const override { return stats().triggers; }

 private:
  bool decodeNextBlock(EventArray& block) override;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace eds
