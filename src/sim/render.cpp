#include "sim/render.hpp"

#include <tbb/blocked_range.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/parallel.hpp"

namespace eds::sim {

namespace {

int mirrorIndex(int i, int n) {
  if (n == 1) return 0;
  const int period = 2 * (n - 1);
  i %= period;
  if (i < 0) i += period;
  return i < n ? i : period - i;
}

}  // namespace

float sampleBilinearMirror(const cv::Mat& tex, double col, double row) {
  const double fc = std::floor(col), fr = std::floor(row);
  const float ac = static_cast<float>(col - fc), ar = static_cast<float>(row - fr);
  const int c0 = static_cast<int>(fc), r0 = static_cast<int>(fr);
  const int w = tex.cols, h = tex.rows;
  int ca = c0, cb = c0 + 1, ra = r0, rb = r0 + 1;
  if (c0 < 0 || c0 + 1 >= w) ca = mirrorIndex(c0, w), cb = mirrorIndex(c0 + 1, w);
  if (r0 < 0 || r0 + 1 >= h) ra = mirrorIndex(r0, h), rb = mirrorIndex(r0 + 1, h);
  const float* pa = tex.ptr<float>(ra);
  const float* pb = tex.ptr<float>(rb);
  const float top = pa[ca] + ac * (pa[cb] - pa[ca]);
  const float bot = pb[ca] + ac * (pb[cb] - pb[ca]);
  return top + ar * (bot - top);
}

struct Renderer::PlaneInView {
  const Plane* plane;
  const cv::Mat* texture;
  // For ray d = (x, y, 1): depth s = num / (n . d); texture column = s (u . d) - u . c + offset.
  double nx, ny, nz, num;
  double ux, uy, uz, uc, vx, vy, vz, vc;
  double half_u, half_v;  // rectangle half-sizes in texels (unbounded if mirror_outside)
  double col0, row0;      // texel coordinates of the centre
  int x0, x1, y0, y1;     // supersampled pixel bounding box (inclusive)
};

Renderer::Renderer(const Scene& scene, const CameraModel& camera, RenderOptions opts)
    : scene_(scene), camera_(camera), opts_(opts) {
  if (camera.width <= 0 || camera.height <= 0) throw std::invalid_argument("Renderer: camera without size");
  if (opts.supersample < 1 || opts.supersample > 8) throw std::invalid_argument("Renderer: supersample 1..8");
  if (scene.textures.size() != scene.texture_specs.size() || scene.textures.empty())
    throw std::invalid_argument("Renderer: scene textures are not loaded");
  const int ss = opts.supersample;
  ss_w_ = camera.width * ss;
  ss_h_ = camera.height * ss;
  ray_x_.resize(static_cast<std::size_t>(ss_w_) * ss_h_);
  ray_y_.resize(ray_x_.size());
  for (int y = 0; y < ss_h_; ++y) {
    for (int x = 0; x < ss_w_; ++x) {
      // Sub-pixel sample centres, evenly spread over the pixel's square.
      const Vec2 px((x + 0.5) / ss - 0.5, (y + 0.5) / ss - 0.5);
      const Vec3 ray = camera.unproject(px);
      ray_x_[y * ss_w_ + x] = static_cast<float>(ray.x());
      ray_y_[y * ss_w_ + x] = static_cast<float>(ray.y());
    }
  }
  centre_x_.resize(static_cast<std::size_t>(camera.width) * camera.height);
  centre_y_.resize(centre_x_.size());
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const Vec3 ray = camera.unproject(Vec2(x, y));
      centre_x_[y * camera.width + x] = static_cast<float>(ray.x());
      centre_y_[y * camera.width + x] = static_cast<float>(ray.y());
    }
}

void Renderer::prepare(const SE3& T_w_c, std::vector<PlaneInView>& out) const {
  const SE3 T_c_w = T_w_c.inverse();
  const Mat3 R_c_w = T_c_w.rotationMatrix();
  const int ss = opts_.supersample;
  constexpr double kNear = 0.01;
  for (const Plane& pl : scene_.planes) {
    PlaneInView v{};
    v.plane = &pl;
    v.texture = &scene_.textures.at(pl.texture);
    const Vec3 c = T_c_w * pl.center;
    const Vec3 u = R_c_w * pl.u, vv = R_c_w * pl.v;
    const Vec3 n = u.cross(vv);
    v.nx = n.x(), v.ny = n.y(), v.nz = n.z(), v.num = n.dot(c);
    if (std::abs(v.num) < 1e-9) continue;  // camera in the plane: it sees it edge-on
    const double inv_texel = 1.0 / pl.texel;
    v.ux = u.x() * inv_texel, v.uy = u.y() * inv_texel, v.uz = u.z() * inv_texel, v.uc = u.dot(c) * inv_texel;
    v.vx = vv.x() * inv_texel, v.vy = vv.y() * inv_texel, v.vz = vv.z() * inv_texel,
    v.vc = vv.dot(c) * inv_texel;
    v.col0 = v.texture->cols / 2.0;
    v.row0 = v.texture->rows / 2.0;
    if (scene_.mirror_outside) {
      v.half_u = v.half_v = std::numeric_limits<double>::infinity();
      v.x0 = 0, v.y0 = 0, v.x1 = ss_w_ - 1, v.y1 = ss_h_ - 1;
    } else {
      v.half_u = 0.5 * pl.size_u * inv_texel;
      v.half_v = 0.5 * pl.size_v * inv_texel;
      // Outline sampled densely (distortion bends straight edges), clipped to z > near.
      double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
      bool any = false, behind = false;
      const Vec3 corners[4] = {
          c - 0.5 * pl.size_u * u - 0.5 * pl.size_v * vv, c + 0.5 * pl.size_u * u - 0.5 * pl.size_v * vv,
          c + 0.5 * pl.size_u * u + 0.5 * pl.size_v * vv, c - 0.5 * pl.size_u * u + 0.5 * pl.size_v * vv};
      constexpr int kSteps = 24;
      for (int e = 0; e < 4; ++e) {
        const Vec3& a = corners[e];
        const Vec3& b = corners[(e + 1) % 4];
        for (int s = 0; s <= kSteps; ++s) {
          const Vec3 p = a + (b - a) * (static_cast<double>(s) / kSteps);
          if (p.z() < kNear) {
            behind = true;
            continue;
          }
          const Vec2 px = camera_.project(p);
          xmin = std::min(xmin, px.x()), xmax = std::max(xmax, px.x());
          ymin = std::min(ymin, px.y()), ymax = std::max(ymax, px.y());
          any = true;
        }
      }
      if (!any) continue;  // entirely behind the camera
      if (behind) {
        // Part of the outline is behind the camera: its projection is unbounded; take the image.
        xmin = ymin = -1e300;
        xmax = ymax = 1e300;
      }
      const double m = 2.0;  // pixels of margin for sampling the outline
      v.x0 = static_cast<int>(std::max(0.0, std::floor((xmin - m + 0.5) * ss)));
      v.x1 = static_cast<int>(std::min<double>(ss_w_ - 1, std::ceil((xmax + m + 0.5) * ss)));
      v.y0 = static_cast<int>(std::max(0.0, std::floor((ymin - m + 0.5) * ss)));
      v.y1 = static_cast<int>(std::min<double>(ss_h_ - 1, std::ceil((ymax + m + 0.5) * ss)));
      if (v.x0 > v.x1 || v.y0 > v.y1) continue;
    }
    out.push_back(v);
  }
}

void Renderer::render(const SE3& T_w_c, cv::Mat& intensity, cv::Mat* depth) const {
  std::vector<PlaneInView> planes;
  planes.reserve(scene_.planes.size());
  prepare(T_w_c, planes);
  const int ss = opts_.supersample;
  const int W = camera_.width, H = camera_.height;
  intensity.create(H, W, CV_32F);
  if (depth) depth->create(H, W, CV_32F);
  const float inv_ss2 = 1.0f / static_cast<float>(ss * ss);
  // Rows of output pixels in parallel; each works on its own supersampled rows.
  parallelFor(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& rows) {
    std::vector<double> zbuf(static_cast<std::size_t>(ss_w_) * ss);
    std::vector<int> hit(zbuf.size());
    std::vector<float> acc(W);
    for (int y = rows.begin(); y < rows.end(); ++y) {
      std::fill(acc.begin(), acc.end(), 0.0f);
      for (int sy = 0; sy < ss; ++sy) {
        const int yy = y * ss + sy;
        std::fill(zbuf.begin(), zbuf.begin() + ss_w_, std::numeric_limits<double>::infinity());
        std::fill(hit.begin(), hit.begin() + ss_w_, -1);
        const float* rx = &ray_x_[static_cast<std::size_t>(yy) * ss_w_];
        const float* ry = &ray_y_[static_cast<std::size_t>(yy) * ss_w_];
        for (int k = 0; k < static_cast<int>(planes.size()); ++k) {
          const PlaneInView& p = planes[k];
          if (yy < p.y0 || yy > p.y1) continue;
          for (int x = p.x0; x <= p.x1; ++x) {
            const double den = p.nx * rx[x] + p.ny * ry[x] + p.nz;
            const double s = p.num / den;
            if (!(s > 1e-3) || s >= zbuf[x]) continue;
            const double a = s * (p.ux * rx[x] + p.uy * ry[x] + p.uz) - p.uc;
            const double b = s * (p.vx * rx[x] + p.vy * ry[x] + p.vz) - p.vc;
            if (std::abs(a) > p.half_u || std::abs(b) > p.half_v) continue;
            zbuf[x] = s;
            hit[x] = k;
          }
        }
        for (int x = 0; x < ss_w_; ++x) {
          float val = static_cast<float>(opts_.background);
          if (hit[x] >= 0) {
            const PlaneInView& p = planes[hit[x]];
            const double s = zbuf[x];
            const double a = s * (p.ux * rx[x] + p.uy * ry[x] + p.uz) - p.uc;
            const double b = s * (p.vx * rx[x] + p.vy * ry[x] + p.vz) - p.vc;
            val = sampleBilinearMirror(*p.texture, a + p.col0, b + p.row0);
          }
          acc[x / ss] += val;
        }
      }
      float* out = intensity.ptr<float>(y);
      for (int x = 0; x < W; ++x) out[x] = acc[x] * inv_ss2;
      if (depth) {
        // Depth of the pixel centre's ray: nearest plane hit (z-depth = ray parameter, as z = 1).
        float* d = depth->ptr<float>(y);
        for (int x = 0; x < W; ++x) {
          const double rxc = centre_x_[y * W + x], ryc = centre_y_[y * W + x];
          double best = std::numeric_limits<double>::infinity();
          for (const PlaneInView& p : planes) {
            const double s = p.num / (p.nx * rxc + p.ny * ryc + p.nz);
            if (!(s > 1e-3) || s >= best) continue;
            const double a = s * (p.ux * rxc + p.uy * ryc + p.uz) - p.uc;
            const double b = s * (p.vx * rxc + p.vy * ryc + p.vz) - p.vc;
            if (std::abs(a) > p.half_u || std::abs(b) > p.half_v) continue;
            best = s;
          }
          d[x] = std::isfinite(best) ? static_cast<float>(best) : 0.0f;
        }
      }
    }
  });
}

}  // namespace eds::sim
