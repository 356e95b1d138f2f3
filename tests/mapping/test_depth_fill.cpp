#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "mapping/depth_fill.hpp"

namespace eds {
namespace {

TEST(DepthFill, NearestProjectionMatchesBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(0, 240), V(0, 180);
  std::uniform_real_distribution<double> R(0.2, 2.0);
  std::vector<ProjectedPoint> proj(500);
  for (auto& p : proj) p = {U(rng), V(rng), R(rng)};
  std::vector<cv::Point> px;
  for (int i = 0; i < 300; ++i) px.emplace_back(static_cast<int>(U(rng)), static_cast<int>(V(rng)));
  DepthFillConfig cfg;
  cfg.neighbours = 1;
  cfg.max_distance_px = 1e9;
  const std::vector<double> rho = fillInverseDepth(px, proj, cfg);
  for (std::size_t i = 0; i < px.size(); ++i) {
    const auto best = std::min_element(proj.begin(), proj.end(), [&](const auto& a, const auto& b) {
      const auto d = [&](const ProjectedPoint& q) {
        return (q.u - px[i].x) * (q.u - px[i].x) + (q.v - px[i].y) * (q.v - px[i].y);
      };
      return d(a) < d(b);
    });
    EXPECT_DOUBLE_EQ(rho[i], best->inv_depth) << i;
  }
}

TEST(DepthFill, MedianOfNeighboursAndReach) {
  // Three projections near (10, 10), one of them an outlier (occluding surface); one far away.
  const std::vector<ProjectedPoint> proj = {{10, 10, 1.0}, {11, 10, 1.1}, {10, 11, 5.0}, {100, 100, 0.5}};
  DepthFillConfig cfg;
  cfg.neighbours = 3;
  cfg.max_distance_px = 5;
  const std::vector<double> rho = fillInverseDepth({{10, 10}, {100, 101}, {50, 50}}, proj, cfg);
  EXPECT_DOUBLE_EQ(rho[0], 1.1);  // median of 1.0, 1.1, 5.0
  EXPECT_DOUBLE_EQ(rho[1], 0.5);  // only one within reach
  EXPECT_EQ(rho[2], 0.0);         // none within reach: unknown
  EXPECT_EQ(fillInverseDepth({{1, 1}}, {}, cfg)[0], 0.0);
  // The reach is a distance in pixels: 4 px away is within 5, 6 px is not.
  const std::vector<double> edge = fillInverseDepth({{200, 104}, {200, 106}}, {{200, 100, 0.7}}, cfg);
  EXPECT_DOUBLE_EQ(edge[0], 0.7);
  EXPECT_EQ(edge[1], 0.0);
}

TEST(DepthFill, ProjectsIntoTheKeyframe) {
  CameraModel cam;
  cam.width = 240, cam.height = 180, cam.fx = cam.fy = 200, cam.cx = 119.5, cam.cy = 89.5;
  const SE3 T_w_kf(SO3::exp(Vec3(0.01, -0.02, 0.03)), Vec3(0.1, 0.2, -0.3));
  const Vec3 p_kf(0.1, -0.05, 2.0);
  const std::vector<Vec3> p_w = {T_w_kf * p_kf, T_w_kf * Vec3(0, 0, -1), T_w_kf * Vec3(10, 0, 1)};
  const auto out = projectPoints(p_w, T_w_kf, cam);
  ASSERT_EQ(out.size(), 1u);  // behind the camera and outside the image are dropped
  EXPECT_NEAR(out[0].u, 200 * 0.05 + 119.5, 1e-4);
  EXPECT_NEAR(out[0].v, 200 * -0.025 + 89.5, 1e-4);
  EXPECT_NEAR(out[0].inv_depth, 0.5, 1e-12);
}

TEST(DepthFill, MedianFilterRemovesNoiseAndKeepsADepthEdge) {
  // Two surfaces: inverse depth 1 on the left half, 0.25 on the right; 10 % noise on every point.
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 0.1);
  std::vector<cv::Point2f> px;
  std::vector<double> rho, truth;
  for (int y = 0; y < 60; y += 2)
    for (int x = 0; x < 80; x += 2) {
      px.emplace_back(x, y);
      truth.push_back(x < 40 ? 1.0 : 0.25);
      rho.push_back(truth.back() * (1.0 + n(rng)));
    }
  rho[5] = 0.0;  // unknown stays unknown
  const auto rms = [&](const std::vector<double>& r) {
    double ss = 0;
    int c = 0;
    for (std::size_t i = 0; i < r.size(); ++i)
      if (r[i] > 0) ss += std::pow(r[i] / truth[i] - 1.0, 2), ++c;
    return std::sqrt(ss / c);
  };
  const double before = rms(rho);
  medianFilterInverseDepth(px, rho, 6.0);
  const double after = rms(rho);
  std::printf("[ median ] relative inverse-depth error %.1f %% -> %.1f %%\n", before * 100, after * 100);
  EXPECT_LT(after, before / 2.5);
  EXPECT_EQ(rho[5], 0.0);
  // Points right at the edge keep their own surface (the median does not average across it).
  for (std::size_t i = 0; i < px.size(); ++i)
    if ((px[i].x == 38 || px[i].x == 40) && rho[i] > 0) EXPECT_NEAR(rho[i], truth[i], 0.35 * truth[i]) << i;
  std::vector<double> wrong(3, 1.0);
  EXPECT_THROW(medianFilterInverseDepth(px, wrong, 6.0), std::invalid_argument);
}

// Every point within the radius and no other, wherever it lies: against all pairs, on points at
// fractional positions, on a pixel grid whose neighbours sit exactly at the radius (left out: the bound
// is strict), and at negative coordinates.
TEST(DepthFill, MedianFilterTakesExactlyThePointsWithinTheRadius) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> pos(-20.f, 200.f);
  std::uniform_real_distribution<double> depth(0.2, 2.0);
  std::vector<cv::Point2f> px;
  for (int i = 0; i < 1500; ++i) px.emplace_back(pos(rng), pos(rng) * 0.5f);
  for (int y = 0; y < 40; y += 4)
    for (int x = 0; x < 40; x += 4) px.emplace_back(static_cast<float>(x), static_cast<float>(y));
  std::vector<double> rho(px.size());
  for (double& r : rho) r = depth(rng);
  rho[7] = 0.0;
  for (const double radius : {4.0, 6.5}) {
    std::vector<double> expected = rho;
    const float r2 = static_cast<float>(radius * radius);
    for (std::size_t i = 0; i < px.size(); ++i) {
      if (!(rho[i] > 0)) continue;
      std::vector<double> near;
      for (std::size_t j = 0; j < px.size(); ++j) {
        const float du = px[i].x - px[j].x, dv = px[i].y - px[j].y;
        if (rho[j] > 0 && du * du + dv * dv < r2) near.push_back(rho[j]);
      }
      std::nth_element(near.begin(), near.begin() + near.size() / 2, near.end());
      expected[i] = near[near.size() / 2];
    }
    std::vector<double> got = rho;
    std::vector<cv::Point2f> uv = px;
    medianFilterInverseDepth(uv, got, radius);
    for (std::size_t i = 0; i < px.size(); ++i)
      ASSERT_EQ(got[i], expected[i]) << "point " << i << " radius " << radius;
  }
}

}  // namespace
}  // namespace eds
