#pragma once
// eds's own HDF5 layout: one file holds a whole recording, so that any input `eds convert` reads
// becomes a fast one whose times are kept to the nanosecond.
//   root attributes: eds_layout = 1, source_format (string), width, height (the sensor's; 0 unknown)
//   events/{x, y: uint16; t: int64 ns after t_offset; p: uint8 0/1}, t_offset (int64 ns), ms_to_idx
//   (ms_to_idx[i]: the first event with t >= i ms): DSEC's layout with nanosecond times
//   frames/images: N x H x W uint8, frames/t: int64 ns
//   calibration: attributes model ("none", "radtan", "equidistant"), width, height, fx, fy, cx, cy,
//                k (5 doubles), source (string)
//   ground_truth/t: int64 ns, ground_truth/T_w_c: N x 7 float64 (tx ty tz qx qy qz qw)
//   imu/t: int64 ns, imu/acc: N x 3 (m/s^2), imu/gyro: N x 3 (rad/s)
//   triggers/t: int64 ns, triggers/channel: uint8, triggers/rising: uint8
// Each group is present only when the recording has that stream. Events and frames are appended as
// they are read; the file appears under its name only once finish() completes it.
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/events.hpp"
#include "io/trajectory_io.hpp"

namespace eds {

// Everything of an eds HDF5 recording but its events and frames (which stream).
struct EdsHdf5Contents {
  std::string source_format;
  int width = 0, height = 0;  // the sensor's size (0: unknown)
  std::optional<CameraModel> camera;
  std::string calibration_source;
  Trajectory ground_truth;
  std::vector<ImuSample> imu;
  std::vector<TriggerEvent> triggers;
  bool has_events = false;  // set by readEdsHdf5 (the writer knows from appendEvents)
};

// Reads the non-streamed parts; InputError naming the file for a malformed layout.
EdsHdf5Contents readEdsHdf5(const std::filesystem::path& file);

class EdsHdf5Writer {
 public:
  // `compress`: gzip (level 1, byte shuffle) on events and frames: ~3x smaller, slower to read.
  EdsHdf5Writer(const std::filesystem::path& target, const std::string& source_format, bool compress);
  ~EdsHdf5Writer();  // an unfinished file is removed
  EdsHdf5Writer(const EdsHdf5Writer&) = delete;
  EdsHdf5Writer& operator=(const EdsHdf5Writer&) = delete;

  // Events in time order (checked across calls); std::invalid_argument otherwise.
  void appendEvents(const EventArray& events);
  // An 8-bit gray frame; all frames share one size and come in increasing time.
  void appendFrame(TimeNs t, const cv::Mat& gray);
  // Writes the remaining streams, closes the file and renames it to the target.
  void finish(const EdsHdf5Contents& rest);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace eds
