#include "mapping/depth_fill.hpp"

#include <algorithm>
#include <array>
#include <nanoflann.hpp>
#include <stdexcept>

namespace eds {

namespace {
// nanoflann's dataset adaptor over the projections' pixel coordinates.
struct ProjectionCloud {
  const std::vector<ProjectedPoint>& pts;
  std::size_t kdtree_get_point_count() const { return pts.size(); }
  float kdtree_get_pt(std::size_t i, std::size_t dim) const { return dim == 0 ? pts[i].u : pts[i].v; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, ProjectionCloud>,
                                                 ProjectionCloud, 2, std::size_t>;
}  // namespace

std::vector<ProjectedPoint> projectPoints(const std::vector<Vec3>& p_w, const SE3& T_w_kf,
                                          const CameraModel& cam) {
  const SE3 T_kf_w = T_w_kf.inverse();
  std::vector<ProjectedPoint> out;
  out.reserve(p_w.size());
  for (const Vec3& pw : p_w) {
    const Vec3 p = T_kf_w * pw;
    if (p.z() <= 1e-6) continue;
    const double u = cam.fx * p.x() / p.z() + cam.cx, v = cam.fy * p.y() / p.z() + cam.cy;
    if (u < 0 || v < 0 || u > cam.width - 1 || v > cam.height - 1) continue;
    out.push_back({static_cast<float>(u), static_cast<float>(v), 1.0 / p.z()});
  }
  return out;
}

std::vector<double> fillInverseDepth(const std::vector<cv::Point>& pixels,
                                     const std::vector<ProjectedPoint>& projected,
                                     const DepthFillConfig& cfg) {
  std::vector<double> out(pixels.size(), 0.0);
  if (projected.empty()) return out;
  const ProjectionCloud cloud{projected};
  const Tree tree(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  const std::size_t k = std::clamp<std::size_t>(cfg.neighbours, 1, 16);
  std::array<std::size_t, 16> idx{};
  std::array<float, 16> d2{};
  std::array<double, 16> rho{};
  const float max2 = static_cast<float>(cfg.max_distance_px * cfg.max_distance_px);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const float q[2] = {static_cast<float>(pixels[i].x), static_cast<float>(pixels[i].y)};
    const std::size_t n = tree.knnSearch(q, k, idx.data(), d2.data());
    std::size_t m = 0;
    for (std::size_t j = 0; j < n; ++j)
      if (d2[j] <= max2) rho[m++] = projected[idx[j]].inv_depth;
    if (m == 0) continue;
    // The median of the nearest few: robust to a stray point from an occluding surface.
    std::nth_element(rho.begin(), rho.begin() + m / 2, rho.begin() + m);
    out[i] = rho[m / 2];
  }
  return out;
}

void medianFilterInverseDepth(std::vector<cv::Point2f>& px, std::vector<double>& inv_depth,
                              double radius_px) {
  if (px.size() != inv_depth.size()) throw std::invalid_argument("medianFilterInverseDepth: size mismatch");
  std::vector<ProjectedPoint> pts;
  std::vector<std::size_t> which;
  for (std::size_t i = 0; i < px.size(); ++i)
    if (inv_depth[i] > 0) pts.push_back({px[i].x, px[i].y, inv_depth[i]}), which.push_back(i);
  if (pts.empty() || !(radius_px > 0)) return;
  const ProjectionCloud cloud{pts};
  const Tree tree(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  std::vector<std::pair<std::size_t, float>> hits;
  std::vector<double> rho;
  nanoflann::SearchParams params;
  params.sorted = false;
  const float r2 = static_cast<float>(radius_px * radius_px);
  for (std::size_t j = 0; j < pts.size(); ++j) {
    const float q[2] = {pts[j].u, pts[j].v};
    tree.radiusSearch(q, r2, hits, params);
    rho.clear();
    for (const auto& h : hits) rho.push_back(pts[h.first].inv_depth);
    std::nth_element(rho.begin(), rho.begin() + rho.size() / 2, rho.end());
    inv_depth[which[j]] = rho[rho.size() / 2];
  }
}

}  // namespace eds
