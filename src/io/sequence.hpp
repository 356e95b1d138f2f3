#pragma once
// A recorded (or simulated) sequence on disk in the ECD folder layout:
//   events.txt | events.txt.gz | events.h5   events (optional)
//   images.txt + images/                     frames (optional)
//   calib.txt | camchain.yaml                calibration (ECD line or Kalibr camchain)
//   groundtruth.txt                          T_w_c in TUM order (optional)
//   depth/<frame name>.png                   z-depth in mm, uint16 (optional, simulated data)
// Files are opened only when asked for, so a frames-only or events-only sequence works, and a file is
// "missing" only when the requested work needs it.
// A sequence can also be one recording file, told by its content: an AEDAT 4.0 file (events, frames,
// IMU), a Prophesee EVT 2.0/3.0 `.raw` file, a ROS 1 bag, a rosbag2 (`.db3`, `.mcap`, or its folder)
// an HDF5 event file (DSEC / TUM-VIE / VECtor layout), an MVSEC or M3ED HDF5 file (events and frames)
// or eds's own HDF5 layout (everything, written by `eds convert`). Bags also
// give frames (sensor_msgs/Image), calibration (sensor_msgs/CameraInfo) and ground truth (PoseStamped /
// TransformStamped); --calib overrides.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "io/event_source.hpp"
#include "io/hdf5_layouts.hpp"
#include "io/trajectory_io.hpp"

namespace eds {

struct FrameRef {
  TimeNs t = 0;
  std::filesystem::path path;  // the image file (folders)
  std::uint64_t offset = 0;    // where the frame is inside a recording file
  TimeNs exposure = 0;         // as the recording gives it (AEDAT 4.0); 0: not recorded
};

// How the events of a sequence are stored.
enum class EventStorage { kNone, kEcdText, kHdf5, kHdf5Mvsec, kHdf5Eds, kPropheseeRaw, kRosBag, kAedat4 };

struct SequenceOptions {
  std::string events_topic;   // bags: the topic to read events from (empty: the only event topic)
  std::string image_topic;    // bags: the sensor_msgs/Image topic of the frames
  std::string gt_topic;       // bags: the PoseStamped / TransformStamped topic of the ground truth
  int width = 0, height = 0;  // sensor size where the recording does not give it (.raw files)
};

class Sequence {
 public:
  // Scans the folder; parses images.txt and the calibration (small files) eagerly so their errors
  // surface at once. Throws InputError if the folder does not exist or holds neither events nor frames.
  explicit Sequence(const std::filesystem::path& dir, const SequenceOptions& options = {});

  const std::filesystem::path& dir() const { return dir_; }
  // What the input is: "ECD folder", "Prophesee EVT 3.0", "ROS 1 bag", "rosbag2 (sqlite3)", ...
  const std::string& format() const { return format_; }
  EventStorage eventStorage() const { return event_storage_; }
  // Where frames are (or would be) listed: dir/images.txt, or the recording file.
  std::filesystem::path framesSource() const;
  bool hasEvents() const { return !events_file_.empty(); }
  bool hasFrames() const { return !frames_.empty(); }
  bool hasGroundTruth() const;
  bool hasCalibration() const { return camera_.has_value(); }
  // Where the calibration came from: a file, a bag topic, --calib...
  const std::string& calibrationSource() const { return calibration_source_; }
  std::uint64_t imuSamples() const { return imu_.size(); }
  // The recorded IMU samples (AEDAT 4.0, bags), in time order; not used by the odometry yet.
  const std::vector<ImuSample>& imu() const { return imu_; }

  // Calibration with resolution (from the Kalibr file, else the first image, else unknown = 0).
  const CameraModel& camera() const;
  // Replaces the folder's calibration (e.g. with a refined lens from `eds calibrate`). The sensor size
  // stays the sequence's; std::invalid_argument if the camera is invalid or its size disagrees.
  void setCamera(const CameraModel& camera, const std::string& source);
  const std::filesystem::path& eventsFile() const { return events_file_; }
  std::unique_ptr<EventSource> openEvents() const;

  const std::vector<FrameRef>& frames() const { return frames_; }
  // The raw (distorted) 8-bit grayscale frame i; InputError naming the image file if unreadable.
  cv::Mat loadFrame(std::size_t i) const;
  // z-depth in metres (CV_32F) for frame i, from depth/<name>.png; nullopt if there is none.
  std::optional<cv::Mat> loadDepth(std::size_t i) const;

  Trajectory groundTruth() const;  // InputError if groundtruth.txt is missing
  // Sensor size known from calibration or images; 0 when unknown.
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  void openRecordingFile(const std::filesystem::path& file);
  void openRosRecording(const std::filesystem::path& file);
  void openEdsHdf5(const std::filesystem::path& file);

  std::filesystem::path dir_;
  SequenceOptions options_;
  std::string format_ = "ECD folder";
  EventStorage event_storage_ = EventStorage::kNone;
  std::filesystem::path events_file_;
  std::vector<FrameRef> frames_;
  std::optional<CameraModel> camera_;
  std::string calibration_source_;
  std::vector<TriggerEvent> recorded_triggers_;  // eds HDF5 files keep them apart from the events
  int width_ = 0, height_ = 0;
  std::vector<ImuSample> imu_;
  Hdf5FrameDatasets hdf5_frames_;  // where an HDF5 recording keeps its frames (images empty: none)
  std::string hdf5_group_;         // the group of an HDF5 recording's x, y, t, p (empty: "events")
  Trajectory recorded_gt_;         // ground truth read from a recording file
  std::shared_ptr<class RosFrameLoader> ros_frames_;  // decodes a bag's frames on demand
};

// Reads an ECD calib.txt (`fx fy cx cy [k1 k2 p1 p2 [k3]]`, radtan). The size is left at 0.
CameraModel readEcdCalib(const std::filesystem::path& file);
struct KalibrCamera;
// Converts a Kalibr camera to a CameraModel; InputError naming `source` if unsupported or invalid.
CameraModel cameraFromKalibr(const KalibrCamera& k, const std::string& source);
// Reads a calibration file: a Basalt / TUM-VIE JSON (.json; kb4 becomes the equidistant model), a
// DSEC cam_to_cam.yaml (its cam0) or a Kalibr camchain (.yaml/.yml), else an ECD calib.txt line (size
// 0: the sequence gives it).
CameraModel readCameraFile(const std::filesystem::path& file);
// Reads camera `camera` of a Basalt calibration JSON (TUM-VIE's calibration files).
CameraModel readBasaltCalibration(const std::filesystem::path& file, std::size_t camera = 0);
// Reads images.txt (`t images/frame_X.png`); paths relative to the file's folder, checked to exist.
std::vector<FrameRef> readImageList(const std::filesystem::path& file);

}  // namespace eds
