// The epipolar search on a fronto-parallel textured plane seen from two cameras a sideways baseline
// apart: with a unique texture it finds the plane's inverse depth; along a periodic one every few
// pixels match equally well, and the uniqueness test must refuse them.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "mapping/epipolar_search.hpp"

namespace eds {
namespace {

constexpr double kDepth = 2.0, kBaseline = 0.1;

CameraModel camera() {
  CameraModel c;
  c.width = 240, c.height = 180, c.fx = 200, c.fy = 190, c.cx = 119.5, c.cy = 89.5;
  return c;
}

// The image of the plane Z = kDepth (texture as a function of the plane's X, Y) from a camera at
// (cam_x, cam_y, 0).
cv::Mat render(const CameraModel& cam, double cam_x, double cam_y,
               const std::function<double(double, double)>& texture) {
  cv::Mat img(cam.height, cam.width, CV_32F);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u)
      img.at<float>(v, u) = static_cast<float>(
          texture((u - cam.cx) / cam.fx * kDepth + cam_x, (v - cam.cy) / cam.fy * kDepth + cam_y));
  return img;
}

// Bilinear sample between pixel centres, written out here so that the test does not share the
// library's sampler.
double bilinear(const cv::Mat& img, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double ax = x - x0, ay = y - y0;
  const auto at = [&](int r, int c) { return static_cast<double>(img.at<float>(r, c)); };
  return (1 - ay) * ((1 - ax) * at(y0, x0) + ax * at(y0, x0 + 1)) +
         ay * ((1 - ax) * at(y0 + 1, x0) + ax * at(y0 + 1, x0 + 1));
}

struct Result {
  int found = 0, total = 0;
  double worst_rel_error = 0;
  double worst_rms_error = 0;  // reported rms against the pattern's, recomputed at the depth found
};

Result search(const std::function<double(double, double)>& texture, double by = 0.0) {
  const CameraModel cam = camera();
  const cv::Mat host_img = render(cam, 0.0, 0.0, texture), ref_img = render(cam, kBaseline, by, texture);
  SearchFrame host{&host_img, SE3(), 0, 0}, ref{&ref_img, SE3(SO3(), Vec3(kBaseline, by, 0)), 0, 0};
  std::vector<cv::Point> pixels;
  for (int v = 30; v < 150; v += 9)
    for (int u = 60; u < 220; u += 11) pixels.emplace_back(u, v);
  const auto matches = epipolarSearch(host, ref, cam, pixels, 0.2, 1.5, EpipolarSearchConfig{});
  Result r;
  r.total = static_cast<int>(matches.size());
  constexpr int kDsoPattern[8][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0}, {0, 0}, {2, 0}, {-1, 1}, {0, 2}};
  for (std::size_t i = 0; i < matches.size(); ++i) {
    const EpipolarMatch& m = matches[i];
    if (m.inv_depth <= 0) continue;
    ++r.found;
    r.worst_rel_error = std::max(r.worst_rel_error, std::abs(m.inv_depth * kDepth - 1.0));
    // The reference camera is translated by (kBaseline, by, 0): a host pixel at inverse depth ρ moves
    // by −(fx kBaseline, fy by) ρ.
    const double du = -cam.fx * kBaseline * m.inv_depth, dv = -cam.fy * by * m.inv_depth;
    double ss = 0;
    for (const auto& k : kDsoPattern) {
      const int u = pixels[i].x + k[0], v = pixels[i].y + k[1];
      const double e = bilinear(ref_img, u + du, v + dv) - host_img.at<float>(v, u);
      ss += e * e;
    }
    r.worst_rms_error = std::max(r.worst_rms_error, std::abs(std::sqrt(ss / 8) - m.rms));
  }
  return r;
}

// Sums of sines of unrelated periods: nothing repeats over the 26 px search line.
double uniqueTexture(double x, double y) {
  return 0.5 + 0.15 * std::sin(31.0 * x + 2.0 * y) + 0.12 * std::sin(17.3 * x - 23.0 * y + 1.0) +
         0.1 * std::sin(47.0 * y + 7.1 * x);
}

TEST(EpipolarSearch, FindsTheDepthOfAUniqueTexture) {
  const Result r = search(uniqueTexture);
  std::printf("[ epipolar, unique texture ] %d of %d found, worst inverse-depth error %.2f %%\n", r.found,
              r.total, r.worst_rel_error * 100);
  EXPECT_GE(r.found, r.total * 8 / 10);
  EXPECT_LT(r.worst_rel_error, 0.01);
  EXPECT_LT(r.worst_rms_error, 1e-5);
}

// A baseline with a vertical part: the line crosses pixel rows, so the samples along it interpolate
// between rows, and the match's reported pattern RMS must be the one at its depth.
TEST(EpipolarSearch, FindsTheDepthAlongADiagonalLine) {
  const Result r = search(uniqueTexture, 0.043);
  std::printf(
      "[ epipolar, diagonal line ] %d of %d found, worst inverse-depth error %.2f %%, worst rms "
      "error %.2e\n",
      r.found, r.total, r.worst_rel_error * 100, r.worst_rms_error);
  EXPECT_GE(r.found, r.total * 8 / 10);
  EXPECT_LT(r.worst_rel_error, 0.01);
  EXPECT_LT(r.worst_rms_error, 1e-5);
}

TEST(EpipolarSearch, RefusesAPeriodicTextureAlongTheLine) {
  // Stripes across the line with a period of 8 px: three equally good matches on every line.
  const double period_m = 8.0 / 200.0 * kDepth;
  const Result r = search([&](double x, double) { return 0.5 + 0.3 * std::sin(2 * M_PI * x / period_m); });
  std::printf("[ epipolar, periodic texture ] %d of %d found\n", r.found, r.total);
  EXPECT_LE(r.found, r.total / 20);
}

}  // namespace
}  // namespace eds
