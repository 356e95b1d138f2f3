// The relocalizer: a frame far from its keyframe (no starting point an alignment would converge from)
// gets its pose from features at the keyframe's points and a PnP solve; an unrelated view gets none.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "frontend/relocalizer.hpp"
#include "sim_frames.hpp"

namespace eds {
namespace {

CameraModel camera() {
  CameraModel c;
  c.width = 320, c.height = 240;
  c.fx = c.fy = 280;
  c.cx = 159.5, c.cy = 119.5;
  return c;
}

cv::Mat texture(unsigned seed) {
  cv::Mat img(240, 320, CV_32F);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(img, img, cv::Size(0, 0), 1.5);
  cv::normalize(img, img, 0.05, 0.95, cv::NORM_MINMAX);
  return img;
}

Keyframe planeKeyframe(const cv::Mat& img) {
  Keyframe kf;
  kf.image = img;
  for (int y = 4; y < img.rows - 4; y += 3)
    for (int x = 4; x < img.cols - 4; x += 3) kf.points.push_back({float(x), float(y), 0.f, 0.f, 0.5});
  return kf;
}

TEST(Relocalizer, FindsAFrameFarFromItsKeyframe) {
  const CameraModel cam = camera();
  const cv::Mat img = texture(11);
  // 24 cm and 6 degrees from the keyframe: ~35 px of image motion, far beyond an alignment's basin.
  const SE3 T_f_kf(SO3::exp(Vec3(0.03, -0.08, 0.05)), Vec3(0.24, -0.06, 0.1));
  const Relocalization r =
      relocalize(planeKeyframe(img), test::renderPlaneView(img, cam, T_f_kf, 2.0), cam, {});
  ASSERT_TRUE(r.ok) << r.inliers << " of " << r.matches;
  const double t_err = (r.T_f_kf.translation() - T_f_kf.translation()).norm();
  const double r_err = (r.T_f_kf.so3().inverse() * T_f_kf.so3()).angle() * 180 / M_PI;
  std::printf("[ relocalizer ] %d of %d matches, translation error %.2f mm, rotation %.3f deg\n", r.inliers,
              r.matches, t_err * 1e3, r_err);
  EXPECT_GT(r.inliers, 100);
  EXPECT_LT(t_err, 0.01);  // of 2 m depth: the direct alignment takes it from here
  EXPECT_LT(r_err, 0.3);
}

TEST(Relocalizer, AnUnrelatedViewGetsNoPose) {
  const CameraModel cam = camera();
  const Relocalization r = relocalize(planeKeyframe(texture(11)), texture(12), cam, {});
  EXPECT_FALSE(r.ok) << r.inliers << " of " << r.matches << " matches agreed";
}

}  // namespace
}  // namespace eds
