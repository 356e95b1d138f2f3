#pragma once
// Sampling a CV_32F image between pixel centres (centres at integer coordinates): bilinear for the
// frame tracker and the bundle adjustment, bicubic (Catmull-Rom, smooth derivatives) for event frames.
#include <opencv2/core.hpp>

namespace eds {

// Bilinear sample (pixel centres at integers); the caller keeps (x, y) inside [0, w-1) x [0, h-1).
inline float sampleBilinear(const cv::Mat& img, double x, double y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float ax = static_cast<float>(x - x0), ay = static_cast<float>(y - y0);
  const float* r0 = img.ptr<float>(y0) + x0;
  const float* r1 = img.ptr<float>(y0 + 1) + x0;
  return (1 - ay) * ((1 - ax) * r0[0] + ax * r0[1]) + ay * ((1 - ax) * r1[0] + ax * r1[1]);
}

// Bilinear sample and its exact derivatives (constant within a pixel cell along each axis).
inline double sampleBilinear(const cv::Mat& img, double x, double y, double& dx, double& dy) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double ax = x - x0, ay = y - y0;
  const float* r0 = img.ptr<float>(y0) + x0;
  const float* r1 = img.ptr<float>(y0 + 1) + x0;
  const double top = (1 - ax) * r0[0] + ax * r0[1], bot = (1 - ax) * r1[0] + ax * r1[1];
  dx = (1 - ay) * (r0[1] - r0[0]) + ay * (r1[1] - r1[0]);
  dy = bot - top;
  return top + ay * (bot - top);
}

// Bicubic (Catmull-Rom) sample of a CV_32F image with its derivatives in x and y; (x, y) must be at
// least 1 px inside the border (callers check with inside(..., 1.0)); pixel centres at integers.
double sampleBicubic(const cv::Mat& img, double x, double y, double* dx = nullptr, double* dy = nullptr);

}  // namespace eds
