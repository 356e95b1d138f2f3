#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "frontend/exposure_deblur.hpp"
#include "frontend/exposure_estimate.hpp"

namespace eds {
namespace {

constexpr int kW = 80, kH = 6;
constexpr double kContrast = 0.2, kSpeed = 150;  // px/s
constexpr double kFramePeriod = 0.05, kDuration = 0.6;
constexpr double kEps = 1e-3;

// Bright and dark bars 10 px wide with soft edges, moving right at kSpeed; s in seconds.
double intensity(int x, double s) {
  return 0.5 + 0.35 * std::tanh(3 * std::sin(2 * M_PI * (x - kSpeed * s) / 20));
}

struct Recording {
  std::vector<std::pair<TimeNs, cv::Mat>> frames;
  EventArray events;
};

// What an ideal sensor records: events at every threshold crossing of log(I + eps), and 8-bit frames
// every kFramePeriod, each the mean of the intensity over its exposure (centred on its time).
Recording record(double exposure_s) {
  Recording rec;
  constexpr double kStep = 1e-5;
  std::vector<std::tuple<TimeNs, int, int, int>> ev;
  for (int x = 0; x < kW; ++x) {
    double ref = std::log(intensity(x, 0) + kEps);
    for (double s = kStep; s < kDuration; s += kStep) {
      const double L = std::log(intensity(x, s) + kEps);
      for (; L - ref >= kContrast; ref += kContrast)
        for (int y = 0; y < kH; ++y) ev.emplace_back(fromSeconds(s), x, y, 1);
      for (; ref - L >= kContrast; ref -= kContrast)
        for (int y = 0; y < kH; ++y) ev.emplace_back(fromSeconds(s), x, y, -1);
    }
  }
  std::sort(ev.begin(), ev.end());
  for (const auto& [te, x, y, p] : ev) {
    rec.events.t.push_back(te);
    rec.events.x.push_back(static_cast<std::uint16_t>(x));
    rec.events.y.push_back(static_cast<std::uint16_t>(y));
    rec.events.p.push_back(static_cast<std::int8_t>(p));
  }
  for (double t = kFramePeriod; t < kDuration - kFramePeriod; t += kFramePeriod) {
    cv::Mat frame(kH, kW, CV_8UC1);
    constexpr int kSub = 400;
    for (int x = 0; x < kW; ++x) {
      double sum = 0;
      for (int k = 0; k < kSub; ++k) sum += intensity(x, t + exposure_s * ((k + 0.5) / kSub - 0.5));
      frame.col(x).setTo(cv::saturate_cast<std::uint8_t>(255 * sum / kSub));
    }
    rec.frames.emplace_back(fromSeconds(t), frame);
  }
  return rec;
}

// Fed as the odometry feeds it: a frame once every event before its time is in.
ExposureEstimator estimate(const Recording& rec) {
  ExposureEstimator est(cv::Size(kW, kH), kContrast);
  std::size_t i = 0;
  for (const auto& [t, frame] : rec.frames) {
    const std::size_t from = i;
    while (i < rec.events.size() && rec.events.t[i] < t) ++i;
    est.addEvents(rec.events, from, i);
    est.addFrame(t, frame);
    if (est.done()) break;
  }
  return est;
}

TEST(ExposureEstimator, FindsTheExposureOfMotionBlurredFrames) {
  for (const double T : {0.02, 0.04}) {
    const ExposureEstimator est = estimate(record(T));
    ASSERT_TRUE(est.done()) << T;
    std::printf("[ exposure ] true %.1f ms, estimated %.2f ms from %d frame pairs\n", 1e3 * T,
                1e3 * est.exposureSeconds(), est.pairsScored());
    EXPECT_EQ(est.pairsScored(), ExposureEstimator::kPairsNeeded);
    EXPECT_NEAR(est.exposureSeconds(), T, 0.003);
  }
}

// Instantaneous frames: what is left is the sensor's quantization (5 ms), well below the shortest
// exposure the odometry deblurs with.
TEST(ExposureEstimator, SharpFramesNeedNoDeblurring) {
  const ExposureEstimator est = estimate(record(0.0));
  ASSERT_TRUE(est.done());
  std::printf("[ exposure ] sharp frames: estimated %.2f ms\n", 1e3 * est.exposureSeconds());
  EXPECT_LT(est.exposureSeconds(), ExposureDeblurConfig{}.min_exposure_s);
}

// Frames exposed over their whole interval: every pair's minimum is at the longest exposure tried, which
// bounds nothing (early frames of a camera starting to move look the same), so no pair is scored.
TEST(ExposureEstimator, AnExposureAtTheLongestTriedIsNotTakenForAnEstimate) {
  const ExposureEstimator est = estimate(record(kFramePeriod));
  EXPECT_FALSE(est.done());
  EXPECT_EQ(est.pairsScored(), 0);
}

TEST(ExposureEstimator, AStillCameraGivesNoEstimate) {
  ExposureEstimator est(cv::Size(kW, kH), kContrast);
  const cv::Mat frame(kH, kW, CV_8UC1, cv::Scalar(100));
  for (int k = 0; k < ExposureEstimator::kMaxFrames + 5 && !est.done(); ++k)
    est.addFrame(fromSeconds(0.05 * k), frame);
  EXPECT_TRUE(est.done());
  EXPECT_EQ(est.pairsScored(), 0);
  EXPECT_EQ(est.exposureSeconds(), 0.0);
  EXPECT_THROW(ExposureEstimator(cv::Size(2, 2), kContrast), std::invalid_argument);
  EXPECT_THROW(ExposureEstimator(cv::Size(kW, kH), 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace eds
