#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>

#include "frontend/frame_tracker.hpp"

namespace eds {
namespace {

CameraModel camera() {
  CameraModel c;
  c.width = 160, c.height = 120;
  c.fx = c.fy = 140;
  c.cx = 79.5, c.cy = 59.5;
  return c;
}

cv::Mat texture(unsigned seed, double sigma = 2.0) {
  cv::Mat img(120, 160, CV_32F);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(img, img, cv::Size(0, 0), sigma);
  cv::normalize(img, img, 0.1, 0.9, cv::NORM_MINMAX);
  return img;
}

// A fronto-parallel plane at depth 2 m: the keyframe and a frame rendered by warping it exactly.
Keyframe planeKeyframe(const cv::Mat& img) {
  Keyframe kf;
  kf.image = img;
  for (int y = 8; y < img.rows - 8; y += 3)
    for (int x = 8; x < img.cols - 8; x += 3) kf.points.push_back({float(x), float(y), 0.f, 0.f, 0.5});
  return kf;
}

// The keyframe's plane seen from T_f_kf: for each frame pixel, its ray hits the plane z = 2.
cv::Mat planeFrame(const cv::Mat& img, const CameraModel& cam, const SE3& T_f_kf) {
  const SE3 T_kf_f = T_f_kf.inverse();
  cv::Mat frame(img.size(), CV_32F), mx(img.size(), CV_32F), my(img.size(), CV_32F);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const Vec3 ray = T_kf_f.so3() * cam.unproject(Vec2(x, y));
      const Vec3& o = T_kf_f.translation();
      const double s = (2.0 - o.z()) / ray.z();
      const Vec2 u = cam.project(o + s * ray);
      mx.at<float>(y, x) = static_cast<float>(u.x());
      my.at<float>(y, x) = static_cast<float>(u.y());
    }
  cv::remap(img, frame, mx, my, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return frame;
}

TEST(FrameTracker, JacobianMatchesNumericDifferences) {
  const CameraModel cam = camera();
  FrameTrackerConfig cfg;
  cfg.levels = 2;
  FrameTracker ft(cam, cfg);
  const cv::Mat img = texture(3);
  ft.setKeyframe(planeKeyframe(img));
  std::vector<cv::Mat> pyr;
  ft.pyramid(texture(4), pyr);
  const SE3 T(SO3::exp(Vec3(0.01, -0.02, 0.015)), Vec3(0.03, 0.01, -0.02));
  const double a = 0.9, b = 0.05;
  for (int level = 0; level < 2; ++level) {
    std::vector<double> r;
    std::vector<Eigen::Matrix<double, 1, 8>> J;
    const int n = ft.evaluate(level, pyr[level], T, a, b, r, &J);
    ASSERT_GT(n, 100);
    // Numeric derivative of each residual with respect to the 8 parameters, over all residuals.
    for (int k = 0; k < 8; ++k) {
      const double h = 1e-7;
      std::vector<double> rp, rm;
      SE3 Tp = T, Tm = T;
      double ap = a, am = a, bp = b, bm = b;
      if (k < 6) {
        Tp = SE3::exp(Vec6::Unit(k) * h) * T;
        Tm = SE3::exp(-Vec6::Unit(k) * h) * T;
      } else if (k == 6) {
        ap += h, am -= h;
      } else {
        bp += h, bm -= h;
      }
      ASSERT_EQ(ft.evaluate(level, pyr[level], Tp, ap, bp, rp, nullptr), n);
      ASSERT_EQ(ft.evaluate(level, pyr[level], Tm, am, bm, rm, nullptr), n);
      double num = 0, diff = 0;
      for (int i = 0; i < n; ++i) {
        const double nd = (rp[i] - rm[i]) / (2 * h);
        num += nd * nd;
        diff += (nd - J[i](k)) * (nd - J[i](k));
      }
      EXPECT_LT(std::sqrt(diff / num), 1e-4) << "level " << level << " parameter " << k;
    }
  }
}

TEST(FrameTracker, RecoversAKnownMotionOfAPlane) {
  const CameraModel cam = camera();
  FrameTracker ft(cam, {});
  // Smooth texture: the frame is made by resampling, and resampling a sharp texture blurs it, which
  // the affine model would read as a contrast change.
  const cv::Mat img = texture(5, 4.0);
  ft.setKeyframe(planeKeyframe(img));
  const SE3 T_f_kf(SO3::exp(Vec3(0.01, 0.015, -0.01)), Vec3(0.04, -0.02, 0.03));
  cv::Mat frame = planeFrame(img, cam, T_f_kf);
  frame = frame * 1.1 + 0.02;  // an exposure change: the affine brightness must absorb it
  SE3 T;                       // from identity: 2.5 px and ~1 deg away
  double a = 1, b = 0;
  const FrameTrackResult res = ft.track(frame, T, a, b);
  EXPECT_TRUE(res.ok);
  std::printf("[ frame tracker ] rmse %.4f, %d residuals, t err %.3f mm, a %.3f b %.3f\n", res.rmse,
              res.residuals, (T.translation() - T_f_kf.translation()).norm() * 1e3, a, b);
  EXPECT_LT((T.translation() - T_f_kf.translation()).norm(), 2e-3);
  EXPECT_LT((T.so3().inverse() * T_f_kf.so3()).angle() * 180 / M_PI, 0.05);
  EXPECT_NEAR(a, 1.1, 0.03);
  EXPECT_NEAR(b, 0.02, 0.02);
  // min_step ends a level at a tiny rejected step instead of retrying it with more damping: fewer
  // evaluations, the same pose.
  FrameTrackerConfig quick;
  quick.min_step = 1e-5;
  SE3 Tq;
  double aq = 1, bq = 0;
  FrameTracker fq(cam, quick);
  fq.setKeyframe(planeKeyframe(img));
  const FrameTrackResult rq = fq.track(frame, Tq, aq, bq);
  std::printf("[ frame tracker ] %d evaluations, %d with min_step 1e-5\n", res.evaluations, rq.evaluations);
  EXPECT_TRUE(rq.ok);
  EXPECT_LT(rq.evaluations, res.evaluations);
  EXPECT_LT((Tq.inverse() * T).log().norm(), 1e-5);
}

// An overexposed frame: x1.6 and clipped at 0.9, its clipped pixels marked NaN (as a refused frame is
// prepared). Only the pixels that still hold the scene count, and the pose and gain come out right;
// the clipped values themselves would read as a plane of constant brightness.
TEST(FrameTracker, PixelsMarkedNaNAreLeftOut) {
  const CameraModel cam = camera();
  FrameTracker ft(cam, {});
  const cv::Mat img = texture(5, 4.0);
  ft.setKeyframe(planeKeyframe(img));
  const SE3 T_f_kf(SO3::exp(Vec3(0.01, 0.015, -0.01)), Vec3(0.04, -0.02, 0.03));
  cv::Mat frame = cv::min(planeFrame(img, cam, T_f_kf) * 1.6, 0.9);
  frame.setTo(std::numeric_limits<float>::quiet_NaN(), frame >= 0.9f);
  int marked = 0;
  for (auto it = frame.begin<float>(); it != frame.end<float>(); ++it) marked += std::isnan(*it);
  std::printf("[ frame tracker, clipped pixels left out ] %.0f %% of the pixels marked\n",
              100.0 * marked / frame.total());
  ASSERT_GT(marked, static_cast<int>(frame.total() / 4));
  SE3 T;
  double a = 1, b = 0;
  const FrameTrackResult res = ft.track(frame, T, a, b);
  SE3 T_all;
  double a_all = 1, b_all = 0;
  const FrameTrackResult all = ft.track(planeFrame(img, cam, T_f_kf), T_all, a_all, b_all);
  std::printf("[ frame tracker, clipped pixels left out ] %d of %d residuals, t err %.3f mm, a %.3f\n",
              res.residuals, all.residuals, (T.translation() - T_f_kf.translation()).norm() * 1e3, a);
  EXPECT_TRUE(res.ok);
  EXPECT_LT(res.residuals, 2 * all.residuals / 3);
  EXPECT_LT((T.translation() - T_f_kf.translation()).norm(), 2e-3);
  EXPECT_LT((T.so3().inverse() * T_f_kf.so3()).angle() * 180 / M_PI, 0.05);
  EXPECT_NEAR(a, 1.6, 0.05);
}

// A frame with the keyframe's brightness inverted (1 - I): the affine model fits it exactly with a gain
// of -1, which no exposure makes. Such a fit would hand the window a keyframe whose log-gain is NaN;
// the gain stays positive and the frame is not aligned.
TEST(FrameTracker, AFitThatNeedsANegativeGainIsRefused) {
  const CameraModel cam = camera();
  FrameTracker ft(cam, {});
  const cv::Mat img = texture(5, 4.0);
  ft.setKeyframe(planeKeyframe(img));
  const cv::Mat inverted = 1.0 - img;
  SE3 T;
  double a = 1, b = 0;
  const FrameTrackResult res = ft.track(inverted, T, a, b);
  std::printf("[ frame tracker, inverted frame ] ok %d, rmse %.4f, a %.3f, b %.3f\n", res.ok, res.rmse, a, b);
  EXPECT_FALSE(res.ok);
  EXPECT_GT(a, 0.0);
}

}  // namespace
}  // namespace eds
