#pragma once
// What a ROS recording holds besides events, found in one pass over the bag: the frames of an image
// topic (decoded on demand later), the calibration of its CameraInfo topic, the ground truth of a
// PoseStamped / TransformStamped topic, and how many IMU samples there are. Topics are found by type;
// a name chooses among several.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/events.hpp"
#include "io/ros_bag.hpp"
#include "io/trajectory_io.hpp"

namespace eds {

struct RosTopicChoice {
  std::string image, ground_truth;  // empty: the only topic of the type
};

struct RosRecordingIndex {
  std::string image_topic, gt_topic, camera_info_topic;  // empty where the bag has none
  struct Frame {
    TimeNs t = 0;               // the image header's stamp
    std::uint64_t message = 0;  // its index among all messages
  };
  std::vector<Frame> frames;
  std::optional<CameraModel> camera;  // from the first CameraInfo (plumb_bob / equidistant)
  Trajectory ground_truth;            // T_w_c, as the poses are written
  std::string imu_topic;
  std::vector<ImuSample> imu_samples;  // of the first sensor_msgs/Imu topic
};

RosRecordingIndex indexRosRecording(const std::filesystem::path& path, const RosTopicChoice& choice);

// sensor_msgs/Image (mono8, mono16, rgb8, bgr8, rgba8, bgra8) as an 8-bit gray image.
cv::Mat decodeRosImage(RosMessageReader& r);
// sensor_msgs/CameraInfo as a CameraModel.
CameraModel decodeCameraInfo(RosMessageReader& r);

// Reads frames by message index, in any order (fastest in increasing order: one pass over the bag).
class RosFrameLoader {
 public:
  explicit RosFrameLoader(std::filesystem::path path) : path_(std::move(path)) {}
  cv::Mat load(std::uint64_t message);

 private:
  std::filesystem::path path_;
  std::mutex mutex_;
  std::unique_ptr<RosBagReader> bag_;
  std::uint64_t next_index_ = 0;
};

}  // namespace eds
