#pragma once
// A keyframe: the shared state between the front-end (event and frame trackers) and the back-end.
// Images are on the undistorted pinhole grid; points are selected pixels with an inverse depth.
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "core/time.hpp"

namespace eds {

struct KeyframePoint {
  float u = 0, v = 0;    // undistorted pixel
  float gx = 0, gy = 0;  // gradient of the log image at (u, v), per pixel
  double inv_depth = 0;  // 1 / z in the keyframe (0 = unknown)
};

struct Keyframe {
  int id = 0;
  TimeNs t = 0;
  SE3 T_w_kf;
  cv::Mat image;           // CV_32F intensity in [0, 1]
  cv::Mat log_image;       // CV_32F log(image + eps): the L̂ of the event generation model
  cv::Mat grad_x, grad_y;  // CV_32F Sobel gradient of log_image, per pixel (Sobel / 8)
  std::vector<KeyframePoint> points;
};

struct KeyframeImageConfig {
  double log_eps = 1e-3;  // as the simulator's and ESIM's log(I + eps), I in [0, 1]
};

// Fills image, log_image and gradients from an undistorted 8-bit (or CV_32F in [0, 1]) frame.
void setKeyframeImage(Keyframe& kf, const cv::Mat& undistorted, const KeyframeImageConfig& cfg = {});

}  // namespace eds
