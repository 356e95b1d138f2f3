#pragma once
// The options that say how to read a recording file, shared by the commands that open one.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "io/sequence.hpp"

namespace eds::app {

struct RecordingArgs {
  std::string events_topic, image_topic, gt_topic;
  std::string resolution;

  SequenceOptions options() const {
    SequenceOptions o;
    o.events_topic = events_topic;
    o.image_topic = image_topic;
    o.gt_topic = gt_topic;
    char end = 0;
    if (!resolution.empty() && std::sscanf(resolution.c_str(), "%dx%d%c", &o.width, &o.height, &end) != 2)
      throw CLI::ValidationError("--resolution", "expected WxH, e.g. 1280x720, got '" + resolution + "'");
    return o;
  }
};

inline void addRecordingOptions(CLI::App* cmd, RecordingArgs& a) {
  cmd->add_option("--events-topic", a.events_topic,
                  "Bags: the topic to read events from (when there are several)");
  cmd->add_option("--image-topic", a.image_topic, "Bags: the sensor_msgs/Image topic of the frames");
  cmd->add_option("--gt-topic", a.gt_topic,
                  "Bags: the PoseStamped / TransformStamped topic of the ground truth");
  cmd->add_option("--resolution", a.resolution,
                  "Sensor size WxH where the recording does not give it (.raw files)");
}

}  // namespace eds::app
