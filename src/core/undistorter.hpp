#pragma once
// Undistortion to a pinhole camera with the raw camera's fx, fy, cx, cy and size: a remap table for
// images (cv::remap) and a per-pixel lookup table for events, computed once per sequence so that the
// per-event cost is a single load.
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.hpp"

namespace eds {

class Undistorter {
 public:
  explicit Undistorter(const CameraModel& raw);

  const CameraModel& raw() const { return raw_; }
  // The undistorted camera: same intrinsics and size, no distortion.
  const CameraModel& pinhole() const { return pinhole_; }

  // Undistorted pixel of raw pixel (x, y); x < width, y < height.
  const cv::Point2f& eventLut(int x, int y) const { return lut_[y * raw_.width + x]; }
  const std::vector<cv::Point2f>& eventLut() const { return lut_; }

  // Undistorts an image (bilinear); 8-bit or float, any channel count. Pixels whose ray falls outside
  // the raw image (pincushion distortion) take `border` (NaN for a float image whose NaNs mark pixels
  // without information).
  cv::Mat undistortImage(const cv::Mat& raw_image, double border = 0) const;
  const cv::Mat& mapX() const { return map_x_; }
  const cv::Mat& mapY() const { return map_y_; }

 private:
  CameraModel raw_;
  CameraModel pinhole_;
  std::vector<cv::Point2f> lut_;
  cv::Mat map_x_, map_y_;  // CV_32F: undistorted pixel -> raw pixel
};

}  // namespace eds
