#include <gtest/gtest.h>

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
  cfg.removal = 0;
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

TEST(SlidingWindow, RejectsBadRemovalSettings) {
  BackendConfig cfg;
  cfg.min_visible = 1.5;
  EXPECT_THROW(cfg.validate(), std::invalid_argument);
  cfg.min_visible = 0.05;
  cfg.removal = 2;
  EXPECT_THROW(cfg.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace eds
