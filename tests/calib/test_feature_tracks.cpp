// Feature tracks: sub-pixel accuracy on a known image motion, gaps end tracks, bad input is refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "calib/feature_tracks.hpp"

namespace eds {
namespace {

// A smooth random texture (blurred noise), 8-bit.
cv::Mat texture(int w, int h) {
  cv::Mat noise(h, w, CV_32F);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
  cv::Mat out;
  cv::normalize(noise, out, 0, 255, cv::NORM_MINMAX, CV_8U);
  return out;
}

cv::Mat shifted(const cv::Mat& img, double dx, double dy) {
  const cv::Mat M = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
  cv::Mat out;
  cv::warpAffine(img, out, M, img.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  return out;
}

TEST(FeatureTracks, FollowASubPixelShift) {
  const cv::Mat base = texture(320, 240);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 12; ++i) frames.push_back(shifted(base, 0.7 * i, 0.3 * i));
  FeatureTrackConfig cfg;
  cfg.border_px = 12;  // keep clear of the reflected border
  const auto tracks = trackFeatures(frames, cfg);
  ASSERT_GT(tracks.size(), 100u);
  std::vector<double> err;
  for (const auto& t : tracks) {
    ASSERT_EQ(t.frames.size(), t.px.size());
    for (std::size_t j = 1; j < t.frames.size(); ++j) {
      EXPECT_EQ(t.frames[j], t.frames[j - 1] + 1);
      const int n = t.frames[j] - t.frames[0];
      err.push_back((t.px[j] - t.px[0] - Vec2(0.7 * n, 0.3 * n)).norm());
    }
  }
  std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
  EXPECT_LT(err[err.size() / 2], 0.05);  // median drift along the track
  std::size_t full = 0;
  for (const auto& t : tracks) full += t.frames.size() == frames.size();
  EXPECT_GT(full, 100u);  // most features survive the whole (gentle) motion
}

TEST(FeatureTracks, AGapEndsEveryTrack) {
  const cv::Mat base = texture(200, 150);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 10; ++i) frames.push_back(i == 5 ? cv::Mat() : shifted(base, 0.5 * i, 0));
  const auto tracks = trackFeatures(frames, FeatureTrackConfig{});
  ASSERT_FALSE(tracks.empty());
  for (const auto& t : tracks) EXPECT_TRUE(t.frames.back() < 5 || t.frames.front() > 5);
}

TEST(FeatureTracks, RefusesBadInput) {
  std::vector<cv::Mat> frames{texture(100, 80), texture(90, 80)};
  EXPECT_THROW(trackFeatures(frames, {}), std::invalid_argument);
  frames = {cv::Mat(80, 100, CV_32F, cv::Scalar(0))};
  EXPECT_THROW(trackFeatures(frames, {}), std::invalid_argument);
  FeatureTrackConfig bad;
  bad.window_px = 8;
  EXPECT_THROW(trackFeatures({}, bad), std::invalid_argument);
}

}  // namespace
}  // namespace eds
