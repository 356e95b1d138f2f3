#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "frontend/exposure_deblur.hpp"

namespace eds {
namespace {

constexpr int kW = 80, kH = 4;
constexpr double kContrast = 0.2, kExposure = 0.04, kSpeed = 150;  // px/s: 6 px over the exposure
constexpr double kEps = 1e-3;

// A dark-to-bright edge (soft over ~1 px) moving right at kSpeed; s: seconds from the frame's time.
double intensity(int x, double s) {
  const double u = (x - 40.0 - kSpeed * s) / 0.7;
  return 0.15 + 0.7 / (1 + std::exp(-u));
}

// What an ideal sensor sees over the exposure: the frame (the mean of the intensity, 8-bit) and the
// events (a threshold crossing of log(I + eps) by kContrast from the level of the last event), in time
// order.
std::pair<cv::Mat, EventArray> exposeEdge(TimeNs t) {
  constexpr int kSteps = 4000;
  cv::Mat frame(kH, kW, CV_8UC1);
  std::vector<std::tuple<TimeNs, int, int, int>> ev;
  for (int x = 0; x < kW; ++x) {
    double sum = 0, ref = std::log(intensity(x, -kExposure / 2) + kEps);
    for (int k = 0; k < kSteps; ++k) {
      const double s = -kExposure / 2 + kExposure * (k + 0.5) / kSteps;
      sum += intensity(x, s);
      const double L = std::log(intensity(x, s) + kEps);
      for (; L - ref >= kContrast; ref += kContrast)
        for (int y = 0; y < kH; ++y) ev.emplace_back(t + fromSeconds(s), x, y, 1);
      for (; ref - L >= kContrast; ref -= kContrast)
        for (int y = 0; y < kH; ++y) ev.emplace_back(t + fromSeconds(s), x, y, -1);
    }
    for (int y = 0; y < kH; ++y)
      frame.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(255 * sum / kSteps);
  }
  std::sort(ev.begin(), ev.end());
  EventArray out;
  for (const auto& [te, x, y, p] : ev) {
    out.t.push_back(te);
    out.x.push_back(static_cast<std::uint16_t>(x));
    out.y.push_back(static_cast<std::uint16_t>(y));
    out.p.push_back(static_cast<std::int8_t>(p));
  }
  return {frame, out};
}

// Mean absolute difference (gray levels) from the sharp edge at the frame's time, over the pixels the
// edge crosses.
double errorToSharp(const cv::Mat& img) {
  double e = 0;
  int n = 0;
  for (int x = 30; x < 50; ++x, ++n) e += std::abs(img.at<std::uint8_t>(1, x) - 255 * intensity(x, 0));
  return e / n;
}

TEST(ExposureDeblur, EventsOfTheExposureSharpenAMovingEdge) {
  const TimeNs t = fromSeconds(2.0);
  const auto [blurred, events] = exposeEdge(t);
  ASSERT_GT(events.size(), 100u);
  const cv::Mat sharp = deblurFrame(blurred, events, 0, events.size(), t, fromSeconds(kExposure), kContrast);
  const double before = errorToSharp(blurred), after = errorToSharp(sharp);
  std::printf("[ deblur ] %zu events, mean error over the edge %.1f -> %.1f gray levels\n", events.size(),
              before, after);
  // 6.9 -> 2.4: what is left is the sensor's quantization (a pixel knows its brightness to a threshold).
  EXPECT_GT(before, 5.0);
  EXPECT_LT(after, 0.45 * before);
  // Pixels the edge never reached have no events and keep their value.
  EXPECT_EQ(sharp.at<std::uint8_t>(0, 5), blurred.at<std::uint8_t>(0, 5));
  EXPECT_EQ(sharp.at<std::uint8_t>(3, 75), blurred.at<std::uint8_t>(3, 75));
}

TEST(ExposureDeblur, OnlyTheExposuresEventsCount) {
  const TimeNs t = fromSeconds(2.0);
  auto [blurred, events] = exposeEdge(t);
  const cv::Mat sharp = deblurFrame(blurred, events, 0, events.size(), t, fromSeconds(kExposure), kContrast);
  // Events before and after the exposure, and off the sensor, change nothing.
  EventArray more;
  const auto add = [&](TimeNs te, int x, int y) {
    more.t.push_back(te), more.x.push_back(static_cast<std::uint16_t>(x));
    more.y.push_back(static_cast<std::uint16_t>(y)), more.p.push_back(1);
  };
  for (int x = 30; x < 50; ++x) add(t - fromSeconds(0.03), x, 1);
  for (std::size_t i = 0; i < events.size(); ++i) {
    more.t.push_back(events.t[i]), more.x.push_back(events.x[i]), more.y.push_back(events.y[i]);
    more.p.push_back(events.p[i]);
    if (i == events.size() / 2) add(events.t[i], kW + 3, 1);
  }
  for (int x = 30; x < 50; ++x) add(t + fromSeconds(0.03), x, 1);
  const cv::Mat same = deblurFrame(blurred, more, 0, more.size(), t, fromSeconds(kExposure), kContrast);
  EXPECT_EQ(cv::norm(sharp, same, cv::NORM_INF), 0);
  EXPECT_THROW(deblurFrame(cv::Mat(4, 4, CV_32F), events, 0, 0, t, fromSeconds(kExposure), kContrast),
               std::invalid_argument);
  EXPECT_THROW(deblurFrame(blurred, events, 0, 0, t, 0, kContrast), std::invalid_argument);
  EXPECT_THROW((ExposureDeblurConfig{.exposure_s = -0.01}.validate()), std::invalid_argument);
  EXPECT_THROW((ExposureDeblurConfig{.exposure_s = 0.01, .contrast = 0}.validate()), std::invalid_argument);
}

}  // namespace
}  // namespace eds
