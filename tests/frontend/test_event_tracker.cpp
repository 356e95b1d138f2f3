#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "frontend/event_frame.hpp"
#include "frontend/event_tracker.hpp"
#include "frontend/point_selection.hpp"

namespace eds {
namespace {

CameraModel pinhole240() {
  CameraModel c;
  c.width = 240, c.height = 180;
  c.fx = 200, c.fy = 198, c.cx = 119.5, c.cy = 89.5;
  return c;
}

cv::Mat smoothRandomImage(int w, int h, unsigned seed, double sigma) {
  cv::Mat img(h, w, CV_32F);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(img, img, cv::Size(0, 0), sigma);
  return img;
}

TEST(Bicubic, DerivativesMatchNumericDifferences) {
  const cv::Mat img = smoothRandomImage(60, 40, 3, 2.0);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> ux(2, 57), uy(2, 37);
  for (int k = 0; k < 200; ++k) {
    const double x = ux(rng), y = uy(rng), h = 1e-4;
    double dx, dy;
    sampleBicubic(img, x, y, &dx, &dy);
    const double ndx = (sampleBicubic(img, x + h, y) - sampleBicubic(img, x - h, y)) / (2 * h);
    const double ndy = (sampleBicubic(img, x, y + h) - sampleBicubic(img, x, y - h)) / (2 * h);
    EXPECT_NEAR(dx, ndx, 2e-3 * (1 + std::abs(ndx)));
    EXPECT_NEAR(dy, ndy, 2e-3 * (1 + std::abs(ndy)));
  }
  // Interpolates: exact at pixel centres.
  EXPECT_FLOAT_EQ(sampleBicubic(img, 10, 12), img.at<float>(12, 10));
}

TEST(EventFrame, GaussianWeightsBilinearVotesMedianTimeUnitNorm) {
  const Undistorter und(pinhole240());
  EventFrameConfig cfg;
  cfg.num_events = 5;
  cfg.blur = false;
  EventFrameBuilder builder(und, cfg);
  EventArray ev;
  for (int k = 0; k < 5; ++k)
    ev.push_back(1000 + 10 * k, static_cast<std::uint16_t>(50 + k), 60, k % 2 ? -1 : 1);
  EventFrame ef;
  builder.build(ev, 0, ef);
  EXPECT_EQ(ef.t, 1020);
  EXPECT_EQ(ef.t_first, 1000);
  EXPECT_EQ(ef.t_last, 1040);
  EXPECT_NEAR(cv::norm(ef.delta), 1.0, 1e-6);
  // Middle event has weight 1, the ends exp(-0.5 * (2 / (5/6))^2); polarities alternate.
  const float mid = ef.delta.at<float>(60, 52), end = ef.delta.at<float>(60, 50);
  EXPECT_NEAR(end / mid, std::exp(-0.5 * std::pow(2.0 / (5.0 / 6.0), 2)), 1e-5);
  EXPECT_LT(ef.delta.at<float>(60, 51), 0);
  EXPECT_THROW(builder.build(ev, 1, ef), std::out_of_range);
  EventFrameConfig bad;
  bad.overlap = 1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = {};
  bad.num_events = 0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(EventFrame, ReversalCompensationAddsTheEventTheHysteresisHeldBack) {
  // Pixel A fires + + then - -: its first "-" comes a full threshold below the last level, one event
  // late; the builder adds it back at the index midway between A's last "+" and that "-". Pixel B
  // never reverses and is left alone. Pixel C's last event before the packet (index 1) counts too.
  const Undistorter und(pinhole240());
  EventFrameConfig cfg;
  cfg.num_events = 7;
  cfg.blur = false;
  EventArray ev;
  auto add = [&](std::uint16_t x, int p) {
    ev.push_back(1000 + 10 * static_cast<TimeNs>(ev.size()), x, 60, p);
  };
  add(90, 1), add(70, 1), add(91, 1);  // 0-2: before the packet
  add(50, 1), add(50, 1), add(60, 1), add(50, -1), add(60, 1), add(50, -1), add(70, -1);  // 3-9
  auto w = [&](int k) { return std::exp(-0.5 * std::pow((k - 3.0) / (7.0 / 6.0), 2)); };
  EventFrame on, off;
  cfg.reversal_compensation = true;
  EventFrameBuilder(und, cfg).build(ev, 3, on);
  cfg.reversal_compensation = false;
  EventFrameBuilder(und, cfg).build(ev, 3, off);
  const double b = w(2) + w(4);  // pixel B (x = 60), packet indices 2 and 4
  // Without compensation A = w0 + w1 - w3 - w5.
  EXPECT_NEAR(off.delta.at<float>(60, 50) / off.delta.at<float>(60, 60), (w(0) + w(1) - w(3) - w(5)) / b,
              1e-5);
  // With it, A's first "-" (packet index 3, last "+" at 1) adds -w(2); its second "-" adds nothing.
  EXPECT_NEAR(on.delta.at<float>(60, 50) / on.delta.at<float>(60, 60), (w(0) + w(1) - w(3) - w(5) - w(2)) / b,
              1e-5);
  // C: "+" at array index 1, "-" at 9 (packet index 6): the midway index 5 is packet index 2.
  EXPECT_NEAR(on.delta.at<float>(60, 70) / on.delta.at<float>(60, 60), -(w(6) + w(2)) / b, 1e-5);
  EXPECT_NEAR(off.delta.at<float>(60, 70) / off.delta.at<float>(60, 60), -w(6) / b, 1e-5);
}

Keyframe syntheticKeyframe(const CameraModel& cam, int n, unsigned seed) {
  Keyframe kf;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(20, cam.width - 20), uy(20, cam.height - 20), g(-0.5, 0.5),
      d(0.6, 3.0);
  for (int i = 0; i < n; ++i) {
    KeyframePoint p;
    p.u = static_cast<float>(ux(rng));
    p.v = static_cast<float>(uy(rng));
    p.gx = static_cast<float>(g(rng));
    p.gy = static_cast<float>(g(rng));
    p.inv_depth = 1.0 / d(rng);
    kf.points.push_back(p);
  }
  return kf;
}

TEST(EventTracker, JacobianMatchesNumericDifferences) {
  const CameraModel cam = pinhole240();
  EventTracker tracker(cam, {});
  tracker.setKeyframe(syntheticKeyframe(cam, 400, 7));
  const cv::Mat delta = smoothRandomImage(cam.width, cam.height, 11, 3.0);
  const SE3 T(SO3::exp(Vec3(0.01, -0.02, 0.005)), Vec3(0.02, -0.01, 0.03));
  Vec6 nu;
  nu << 0.3, -0.2, 0.1, 0.5, -0.4, 0.2;
  nu.normalize();
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  const int n = tracker.evaluate(delta, T, nu, r, &J);
  ASSERT_GT(n, 300);
  const double h = 1e-6;
  Eigen::MatrixXd Jn(n, 12);
  for (int k = 0; k < 12; ++k) {
    Eigen::VectorXd rp, rm;
    if (k < 6) {
      const Vec6 d = Vec6::Unit(k) * h;
      ASSERT_EQ(tracker.evaluate(delta, SE3::exp(d) * T, nu, rp, nullptr), n);
      ASSERT_EQ(tracker.evaluate(delta, SE3::exp(-d) * T, nu, rm, nullptr), n);
    } else {
      const Vec6 d = Vec6::Unit(k - 6) * h;
      tracker.evaluate(delta, T, nu + d, rp, nullptr);
      tracker.evaluate(delta, T, nu - d, rm, nullptr);
    }
    Jn.col(k) = (rp - rm) / (2 * h);
  }
  for (int k = 0; k < 12; ++k) {
    const double rel = (J.col(k) - Jn.col(k)).norm() / Jn.col(k).norm();
    EXPECT_LT(rel, 1e-4) << "parameter " << k;
  }
}

TEST(EventTracker, EgmRowIsTheGradientDottedWithThePixelFlow) {
  // A pure x-translation of the camera moves a point at depth Z by -fx/Z px per metre along x.
  const CameraModel cam = pinhole240();
  const Row6 a = egmRow(cam, cam.cx, cam.cy, 0.7, 0.0, 0.5);  // Z = 2 m, at the principal point
  Vec6 nu = Vec6::Zero();
  nu[0] = 1.0;
  EXPECT_NEAR(a.dot(nu), -0.7 * (-cam.fx / 2.0), 1e-9);
  nu.setZero();
  nu[4] = 1.0;  // rotation about y: flow -(1 + x^2) fx = -fx at the centre
  EXPECT_NEAR(a.dot(nu), -0.7 * (-cam.fx), 1e-9);
}

TEST(EventTracker, KeyframeWithoutDepthIsAClearError) {
  const CameraModel cam = pinhole240();
  EventTracker tracker(cam, {});
  Keyframe kf = syntheticKeyframe(cam, 10, 1);
  for (auto& p : kf.points) p.inv_depth = 0;
  EXPECT_THROW(tracker.setKeyframe(kf), std::invalid_argument);
}

TEST(PointSelection, SpreadsOverTilesAndHonoursFraction) {
  const cv::Mat img = smoothRandomImage(240, 180, 5, 1.5);
  cv::Mat gx, gy;
  cv::Sobel(img, gx, CV_32F, 1, 0, 3, 1.0 / 8);
  cv::Sobel(img, gy, CV_32F, 0, 1, 3, 1.0 / 8);
  PointSelectionConfig cfg;
  cfg.min_gradient = 0;
  cfg.fraction = 0.1;
  const auto pts = selectPoints(gx, gy, cfg);
  const double usable = (240 - 8) * (180 - 8);
  EXPECT_NEAR(pts.size() / usable, 0.1, 0.02);
  // Every 11x11 tile has its share: no tile left empty.
  int empty_tiles = 0;
  for (int ty = 4; ty + 11 <= 176; ty += 11)
    for (int tx = 4; tx + 11 <= 236; tx += 11) {
      int c = 0;
      for (const auto& p : pts) c += p.x >= tx && p.x < tx + 11 && p.y >= ty && p.y < ty + 11;
      empty_tiles += c == 0;
    }
  EXPECT_EQ(empty_tiles, 0);
  cfg.max_points = 500;
  EXPECT_EQ(selectPoints(gx, gy, cfg).size(), 500u);
}

}  // namespace
}  // namespace eds
