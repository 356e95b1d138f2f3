#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <vector>

#include "frontend/frame_quality.hpp"

namespace eds {
namespace {

// A textured 8-bit frame: uniform noise in [lo, hi].
cv::Mat textured(int lo, int hi, unsigned seed = 1) {
  cv::Mat img(60, 80, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, lo, hi + 1);
  return img;
}

TEST(FrameQuality, RefusesDarkBlownOutFlatAndSuddenlyBrighterFrames) {
  FrameQualityGate gate({});
  for (int k = 0; k < 5; ++k) EXPECT_EQ(gate.check(fromSeconds(0.05 * k), textured(60, 180, k)), "");
  EXPECT_NEAR(gate.referenceMean(), 120, 2);
  EXPECT_TRUE(gate.check(fromSeconds(0.3), textured(0, 5)).starts_with("too dark"));
  EXPECT_TRUE(gate.check(fromSeconds(0.35), textured(240, 255)).starts_with("overexposed"));
  EXPECT_TRUE(gate.check(fromSeconds(0.4), textured(118, 122)).starts_with("low contrast or blurred"));
  // A quarter of the brightness with the same texture per level: an exposure jump, not a dark frame.
  EXPECT_TRUE(gate.check(fromSeconds(0.45), textured(0, 60)).starts_with("sudden exposure change"));
  EXPECT_EQ(gate.check(fromSeconds(0.5), textured(60, 180, 9)), "");
  // The refused frames did not move the reference.
  EXPECT_NEAR(gate.referenceMean(), 120, 2);
}

TEST(FrameQuality, RefusedFrameNormalizedWithItsClippedPixelsLeftOut) {
  // A frame x4 overexposed: the pixels that were under 64 keep their value x4, the others clip at 255.
  const cv::Mat scene = textured(20, 200, 3);
  cv::Mat blown;
  scene.convertTo(blown, CV_8U, 4.0);  // saturates at 255
  const cv::Mat norm = normalizeRefusedFrame(blown, 60.0);
  ASSERT_EQ(norm.type(), CV_32F);
  int clipped = 0, kept = 0;
  double sum = 0;
  for (int y = 0; y < scene.rows; ++y)
    for (int x = 0; x < scene.cols; ++x) {
      const float v = norm.at<float>(y, x);
      if (blown.at<std::uint8_t>(y, x) >= 250) {
        EXPECT_TRUE(std::isnan(v));
        ++clipped;
      } else {
        ASSERT_TRUE(std::isfinite(v));
        sum += v, ++kept;
      }
    }
  EXPECT_GT(clipped, kept);
  // The kept pixels' mean is the reference brightness, and they keep their ratios.
  EXPECT_NEAR(sum / kept, 60.0 / 255, 1e-5);
  std::vector<cv::Point> unclipped;
  for (int x = 0; x < scene.cols && unclipped.size() < 2; ++x)
    if (blown.at<std::uint8_t>(5, x) < 250 &&
        (unclipped.empty() || blown.at<std::uint8_t>(5, x) != blown.at<std::uint8_t>(unclipped[0])))
      unclipped.emplace_back(x, 5);
  ASSERT_EQ(unclipped.size(), 2u);
  const cv::Point a = unclipped[0], b = unclipped[1];
  EXPECT_NEAR(norm.at<float>(a) / norm.at<float>(b),
              double(blown.at<std::uint8_t>(a)) / blown.at<std::uint8_t>(b), 1e-5);
  // Nothing left, or no reference yet: nothing to align.
  EXPECT_TRUE(normalizeRefusedFrame(cv::Mat(60, 80, CV_8UC1, cv::Scalar(255)), 60.0).empty());
  EXPECT_TRUE(normalizeRefusedFrame(cv::Mat(60, 80, CV_8UC1, cv::Scalar(0)), 60.0).empty());
  EXPECT_TRUE(normalizeRefusedFrame(blown, 0.0).empty());
}

}  // namespace
}  // namespace eds
