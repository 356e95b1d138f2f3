#pragma once
// HDF5 layouts of published datasets besides DSEC's (hdf5_events.hpp reads that one, and TUM-VIE's,
// which is the same):
// - MVSEC: `davis/<side>/events`, an N x 4 float64 array of (x, y, t in seconds, polarity -1/+1);
//   `davis/<side>/image_raw`, N x H x W uint8 frames; `davis/<side>/image_raw_ts`, seconds.
// - M3ED: `prophesee/<side>/{x,y,t,p}` (t in µs) with `ms_map_idx` (read by Hdf5EventSource);
//   `ovc/<side>/data`, N x H x W x 1 uint8 frames; `ovc/ts`, µs.
// Events stream in blocks; frames are read one at a time when asked for.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/time.hpp"
#include "io/event_source.hpp"

namespace eds {

enum class Hdf5Layout { kNone, kDsec, kMvsec, kM3ed, kEds };
// Which layout an HDF5 file has, by the datasets in it (left camera).
Hdf5Layout detectHdf5Layout(const std::filesystem::path& file);

// Where a layout keeps its frames.
struct Hdf5FrameDatasets {
  std::string images, times;
  std::int64_t tick_ns = 0;  // 0: float64 seconds (MVSEC), else integers in these units (M3ED µs: 1000)
};
Hdf5FrameDatasets frameDatasets(Hdf5Layout layout);

struct Hdf5FrameIndex {
  std::vector<TimeNs> t;
  int width = 0, height = 0;  // 0 when the file has no frames
};

// The frames' times and size; InputError naming the file for a malformed layout.
Hdf5FrameIndex readHdf5FrameIndex(const std::filesystem::path& file, const Hdf5FrameDatasets& where);
// Frame i as 8-bit gray.
cv::Mat readHdf5Frame(const std::filesystem::path& file, const Hdf5FrameDatasets& where, std::size_t i);

// M3ED keeps each camera's calibration beside its data (`<camera>/calib/{intrinsics, distortion_model,
// distortion_coeffs, resolution, T_to_prophesee_left}`). Its frames come from the OVC imager, another
// camera than the events' unless its T_to_prophesee_left is the identity and its size the same.
struct M3edCalibration {
  std::optional<CameraModel> events;  // prophesee/left/calib, when present
  bool frames_from_another_camera = false;
};
M3edCalibration readM3edCalibration(const std::filesystem::path& file);

class MvsecEventSource : public BlockEventSource {
 public:
  // width/height > 0 check every pixel against the sensor.
  MvsecEventSource(const std::filesystem::path& file, int width, int height,
                   const std::string& side = "left");
  ~MvsecEventSource() override;
  std::optional<std::size_t> size() const override;

 private:
  bool decodeNextBlock(EventArray& block) override;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace eds
