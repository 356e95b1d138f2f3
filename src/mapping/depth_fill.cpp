#include "mapping/depth_fill.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <nanoflann.hpp>
#include <stdexcept>

#include "core/parallel.hpp"

namespace eds {

namespace {
// Below this many queries the neighbour searches cost less than handing them out to threads. Each query
// only reads the input, so the results are the same either way.
constexpr std::size_t kParallelQueries = 2000;

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

// Points sorted into square cells (counting sort): the points of a cell are contiguous.
class PointGrid {
 public:
  PointGrid(const std::vector<ProjectedPoint>& pts, float cell) : cell_(cell) {
    u0_ = v0_ = std::numeric_limits<float>::max();
    float u1 = std::numeric_limits<float>::lowest(), v1 = u1;
    for (const ProjectedPoint& p : pts)
      u0_ = std::min(u0_, p.u), v0_ = std::min(v0_, p.v), u1 = std::max(u1, p.u), v1 = std::max(v1, p.v);
    nx_ = cellOf(u1, u0_) + 1, ny_ = cellOf(v1, v0_) + 1;
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    std::vector<std::size_t> c(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) ++start_[(c[i] = index(pts[i].u, pts[i].v)) + 1];
    for (std::size_t k = 1; k < start_.size(); ++k) start_[k] += start_[k - 1];
    order_.resize(pts.size());
    std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < pts.size(); ++i) order_[fill[c[i]]++] = i;
  }
  // Calls f(i) for every point i in the cells around (u, v) (a superset of those within one cell width).
  template <class F>
  void forEachNear(float u, float v, F&& f) const {
    const int cx = cellOf(u, u0_), cy = cellOf(v, v0_);
    for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, ny_ - 1); ++y)
      for (int x = std::max(cx - 1, 0); x <= std::min(cx + 1, nx_ - 1); ++x) {
        const std::size_t k = static_cast<std::size_t>(y) * nx_ + x;
        for (std::size_t o = start_[k]; o < start_[k + 1]; ++o) f(order_[o]);
      }
  }

 private:
  int cellOf(float a, float a0) const { return static_cast<int>((a - a0) / cell_); }
  std::size_t index(float u, float v) const {
    return static_cast<std::size_t>(cellOf(v, v0_)) * nx_ + cellOf(u, u0_);
  }
  float cell_, u0_, v0_;
  int nx_ = 1, ny_ = 1;
  std::vector<std::size_t> start_, order_;
};
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
  const float max2 = static_cast<float>(cfg.max_distance_px * cfg.max_distance_px);
  forEachChunk(
      pixels.size(),
      [&](int, std::size_t b, std::size_t e) {
        std::array<std::size_t, 16> idx{};
        std::array<float, 16> d2{};
        std::array<double, 16> rho{};
        for (std::size_t i = b; i < e; ++i) {
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
      },
      pixels.size() >= kParallelQueries);
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
  // The points binned in square cells as wide as the radius: each query reads the 3x3 cells around its
  // own, a few times faster than a k-d tree's radius search for the tens of neighbours a query has.
  const PointGrid grid(pts, static_cast<float>(radius_px));
  const float r2 = static_cast<float>(radius_px * radius_px);
  forEachChunk(
      pts.size(),
      [&](int, std::size_t b, std::size_t e) {
        std::vector<double> rho;
        for (std::size_t j = b; j < e; ++j) {
          rho.clear();
          grid.forEachNear(pts[j].u, pts[j].v, [&](std::size_t k) {
            // The squared distance as a k-d tree over floats computes it, and the same strict bound.
            const float du = pts[j].u - pts[k].u, dv = pts[j].v - pts[k].v;
            if (du * du + dv * dv < r2) rho.push_back(pts[k].inv_depth);
          });
          std::nth_element(rho.begin(), rho.begin() + rho.size() / 2, rho.end());
          inv_depth[which[j]] = rho[rho.size() / 2];
        }
      },
      pts.size() >= kParallelQueries);
}

}  // namespace eds
