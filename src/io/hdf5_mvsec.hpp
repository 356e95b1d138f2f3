#pragma once
// The MVSEC HDF5 layout (one file per sequence and camera side): `davis/<side>/events`, an N x 4
// float64 array of (x, y, t in seconds, polarity -1/+1); `davis/<side>/image_raw`, N x H x W uint8
// frames; `davis/<side>/image_raw_ts`, their times in seconds. Events stream in blocks; frames are
// read one at a time when asked for.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "io/event_source.hpp"

namespace eds {

// True when the HDF5 file has davis/<side>/events (side: "left" or "right").
bool isMvsecFile(const std::filesystem::path& file, const std::string& side = "left");

struct MvsecFrames {
  std::vector<TimeNs> t;
  int width = 0, height = 0;  // 0 when the file has no frames
};

// The frames' times and size; InputError naming the file for a malformed layout.
MvsecFrames readMvsecFrameIndex(const std::filesystem::path& file, const std::string& side = "left");
// Frame i as 8-bit gray.
cv::Mat readMvsecFrame(const std::filesystem::path& file, std::size_t i, const std::string& side = "left");

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
