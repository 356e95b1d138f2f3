#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "backend/sliding_window.hpp"
#include "sim_frames.hpp"

namespace eds {
namespace {

// A window of keyframes looking along +z from positions on the x axis; each hosts a grid of points at
// depth `depth` (points far away stay in view of every keyframe; near ones leave it).
SlidingWindow windowAlong(const std::vector<double>& xs, const BackendConfig& cfg,
                          const std::vector<double>& depth) {
  const CameraModel cam = test::simCamera();
  SlidingWindow w(cam, cfg);
  const cv::Mat image(cam.height, cam.width, CV_32F, cv::Scalar(0.5f));
  for (std::size_t k = 0; k < xs.size(); ++k) {
    std::vector<KeyframePoint> pts;
    for (int v = 20; v < cam.height - 20; v += 20)
      for (int u = 20; u < cam.width - 20; u += 20) {
        KeyframePoint p;
        p.u = static_cast<float>(u), p.v = static_cast<float>(v);
        p.inv_depth = 1.0 / depth[k];
        pts.push_back(p);
      }
    w.addKeyframe(static_cast<int>(k), static_cast<TimeNs>(k), SE3(SO3(), Vec3(xs[k], 0, 0)), 0, 0, image,
                  pts);
  }
  return w;
}

TEST(SlidingWindow, DsoRuleDropsTheKeyframeCrowdedByItsNeighbours) {
  BackendConfig cfg;
  cfg.window = 7;
  // Keyframes 2 and 3 are 5 cm apart, the others 10 cm or more: one of the close pair leaves (the
  // farther from the newest, 2), and the oldest, which gives the longest baseline, stays.
  const std::vector<double> xs = {0.0, 0.1, 0.2, 0.25, 0.4, 0.5, 0.6, 0.7};
  const SlidingWindow w = windowAlong(xs, cfg, std::vector<double>(xs.size(), 50.0));
  EXPECT_EQ(w.keyframeToRemove(), 2);
  cfg.removal = WindowRemoval::kOldest;
  EXPECT_EQ(windowAlong(xs, cfg, std::vector<double>(xs.size(), 50.0)).keyframeToRemove(), 0);
}

TEST(SlidingWindow, DsoRuleDropsAKeyframeOutOfViewFirst) {
  BackendConfig cfg;
  cfg.window = 5;
  // By distance alone keyframe 2 would go (3 is 5 cm from it). Keyframe 1's points are 0.5 m away:
  // from the newest, 0.6 m to the side (fx 200: 240 px), they are all outside the image.
  const std::vector<double> xs = {0.0, 0.15, 0.3, 0.35, 0.6, 0.75};
  std::vector<double> depth(xs.size(), 50.0);
  depth[1] = 0.5;
  EXPECT_EQ(windowAlong(xs, cfg, depth).keyframeToRemove(), 1);
  depth[1] = 50.0;
  EXPECT_EQ(windowAlong(xs, cfg, depth).keyframeToRemove(), 2);
  // The newest two never leave, however crowded.
  EXPECT_LT(windowAlong({0.0, 0.3, 0.6, 0.9, 1.2, 1.21}, cfg, depth).keyframeToRemove(), 4);
}

// Two keyframes at one pose; in the newest a square of the image shows another surface (an occluder
// that came between). The tracking reference keeps the older keyframe's points outside the square and
// drops those behind it, whose photometric error there is an outlier's.
TEST(SlidingWindow, TrackingReferenceDropsPointsHiddenInTheNewestKeyframe) {
  const CameraModel cam = test::simCamera();
  cv::Mat older(cam.height, cam.width, CV_32F), newest;
  cv::RNG rng(7);
  rng.fill(older, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(older, older, cv::Size(0, 0), 0.7);
  newest = older.clone();
  const cv::Rect occluder(100, 60, 60, 60);
  cv::Mat patch = newest(occluder);
  rng.fill(patch, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(patch, patch, cv::Size(0, 0), 0.7);
  // Whole pattern (2 px around the point) on the occluder: hidden; pattern off it entirely: in sight.
  const auto hiddenAt = [&](float u, float v) {
    return u >= occluder.x + 2 && u < occluder.x + occluder.width - 2 && v >= occluder.y + 2 &&
           v < occluder.y + occluder.height - 2;
  };
  const auto inSightAt = [&](float u, float v) {
    return u < occluder.x - 2 || u >= occluder.x + occluder.width + 2 || v < occluder.y - 2 ||
           v >= occluder.y + occluder.height + 2;
  };
  std::vector<KeyframePoint> pts;
  int hidden = 0, in_sight = 0;
  for (int v = 10; v < cam.height - 10; v += 10)
    for (int u = 10; u < cam.width - 10; u += 10) {
      KeyframePoint p;
      p.u = static_cast<float>(u), p.v = static_cast<float>(v), p.inv_depth = 0.5;
      pts.push_back(p);
      hidden += hiddenAt(p.u, p.v);
      in_sight += inSightAt(p.u, p.v);
    }
  ASSERT_GE(hidden, 25);
  BackendConfig cfg;
  cfg.points_per_keyframe = static_cast<int>(pts.size());
  SlidingWindow w(cam, cfg);
  w.addKeyframe(0, 0, SE3(), 0, 0, older, pts);
  w.addKeyframe(1, 1, SE3(), 0, 0, newest, {});
  int ref_hidden = 0, ref_in_sight = 0;
  for (const KeyframePoint& p : w.pointsInNewest()) {
    ref_hidden += hiddenAt(p.u, p.v);
    ref_in_sight += inSightAt(p.u, p.v);
  }
  EXPECT_EQ(ref_in_sight, in_sight);
  EXPECT_LE(ref_hidden, hidden / 10);  // a chance match of 8 pixels at most now and then
}

// Without the points it hosts, the newest keyframe's reference holds the older keyframes' points alone,
// projected into it (the back-end's preliminary reference, before its new points are adjusted).
TEST(SlidingWindow, TrackingReferenceWithoutTheNewestKeyframesOwnPoints) {
  const SlidingWindow w = windowAlong({0.0, 0.1}, BackendConfig{}, {50.0, 50.0});
  const std::vector<KeyframePoint> all = w.pointsInNewest(), older = w.pointsInNewest(false);
  ASSERT_FALSE(older.empty());
  EXPECT_EQ(all.size(), 2 * older.size());
  // Keyframe 0's grid seen from 10 cm to its right at 50 m: shifted left by fx * 0.1 / 50 = 0.4 px.
  for (const KeyframePoint& p : older) {
    EXPECT_NEAR(std::remainder(p.u + 0.4, 20.0), 0.0, 1e-4);
    EXPECT_NEAR(std::remainder(p.v, 20.0), 0.0, 1e-4);
    EXPECT_NEAR(p.inv_depth, 1.0 / 50.0, 1e-9);
  }
  EXPECT_EQ(w.pointsIn(0, false).size(), older.size());  // keyframe 1's grid seen from keyframe 0
}

TEST(SlidingWindow, RejectsBadRemovalSettings) {
  BackendConfig cfg;
  cfg.min_visible = 1.5;
  EXPECT_THROW(cfg.validate(), std::invalid_argument);
  cfg.min_visible = 0.05;
  cfg.removal = static_cast<WindowRemoval>(2);
  EXPECT_THROW(cfg.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace eds
