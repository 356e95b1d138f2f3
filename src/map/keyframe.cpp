#include "map/keyframe.hpp"

#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace eds {

void setKeyframeImage(Keyframe& kf, const cv::Mat& undistorted, const KeyframeImageConfig& cfg) {
  if (undistorted.empty()) throw std::invalid_argument("keyframe: empty image");
  if (undistorted.type() == CV_8U)
    undistorted.convertTo(kf.image, CV_32F, 1.0 / 255.0);
  else if (undistorted.type() == CV_32F)
    kf.image = undistorted.clone();
  else
    throw std::invalid_argument("keyframe: image must be CV_8U or CV_32F");
  cv::log(kf.image + cfg.log_eps, kf.log_image);
  // Sobel's 3x3 kernel weighs the central difference by 8: divide to get a per-pixel derivative,
  // the unit the event generation model's pixel flow needs.
  cv::Sobel(kf.log_image, kf.grad_x, CV_32F, 1, 0, 3, 1.0 / 8.0, 0, cv::BORDER_REPLICATE);
  cv::Sobel(kf.log_image, kf.grad_y, CV_32F, 0, 1, 3, 1.0 / 8.0, 0, cv::BORDER_REPLICATE);
}

}  // namespace eds
