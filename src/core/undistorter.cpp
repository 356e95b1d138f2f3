#include "core/undistorter.hpp"

#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace eds {

Undistorter::Undistorter(const CameraModel& raw) : raw_(raw), pinhole_(raw) {
  if (raw.width <= 0 || raw.height <= 0)
    throw std::invalid_argument("Undistorter: the camera has no resolution");
  pinhole_.distortion = Distortion::kNone;
  pinhole_.k = {};
  lut_.resize(static_cast<std::size_t>(raw.width) * raw.height);
  map_x_.create(raw.height, raw.width, CV_32F);
  map_y_.create(raw.height, raw.width, CV_32F);
  for (int y = 0; y < raw.height; ++y) {
    for (int x = 0; x < raw.width; ++x) {
      const Vec2 u = raw.undistortPixel(Vec2(x, y));
      lut_[y * raw.width + x] = cv::Point2f(static_cast<float>(u.x()), static_cast<float>(u.y()));
      // The image map goes the other way: for each undistorted pixel, where to sample the raw image.
      const Vec2 xn((x - raw.cx) / raw.fx, (y - raw.cy) / raw.fy);
      const Vec2 xd = raw.distort(xn);
      map_x_.at<float>(y, x) = static_cast<float>(raw.fx * xd.x() + raw.cx);
      map_y_.at<float>(y, x) = static_cast<float>(raw.fy * xd.y() + raw.cy);
    }
  }
}

cv::Mat Undistorter::undistortImage(const cv::Mat& raw_image, double border) const {
  if (raw_image.cols != raw_.width || raw_image.rows != raw_.height)
    throw std::invalid_argument("Undistorter: image size differs from the calibration");
  if (raw_.distortion == Distortion::kNone) return raw_image.clone();
  cv::Mat out;
  cv::remap(raw_image, out, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(border));
  return out;
}

}  // namespace eds
