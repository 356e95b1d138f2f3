#include "mapping/epipolar_search.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/image_sampling.hpp"

namespace eds {

namespace {
constexpr int kPattern[8][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0}, {0, 0}, {2, 0}, {-1, 1}, {0, 2}};
}  // namespace

std::vector<EpipolarMatch> epipolarSearch(const SearchFrame& host, const SearchFrame& ref,
                                          const CameraModel& cam, const std::vector<cv::Point>& pixels,
                                          double rho_lo, double rho_hi, const EpipolarSearchConfig& cfg) {
  std::vector<EpipolarMatch> out(pixels.size());
  const SE3 T_r_h = ref.T_w_c.inverse() * host.T_w_c;
  const Mat3 R = T_r_h.rotationMatrix();
  const Vec3 t = T_r_h.translation();
  const double e = std::exp(ref.a - host.a);
  const cv::Mat& Ih = *host.image;
  const cv::Mat& Ir = *ref.image;
  const int W = Ir.cols, H = Ir.rows;
  // Pixel in the reference of host pixel ray x at inverse depth rho: π(R x + rho t) (scaled by rho).
  const auto proj = [&](const Vec3& Rx, double rho, double& u, double& v) {
    const Vec3 q = Rx + rho * t;
    if (q.z() <= 1e-9) return false;
    u = cam.fx * q.x() / q.z() + cam.cx, v = cam.fy * q.y() / q.z() + cam.cy;
    return true;
  };
  const auto inside = [&](double u, double v) { return u >= 3 && v >= 3 && u < W - 4 && v < H - 4; };
  std::array<double, 8> ref_val{};
  std::vector<double> E(cfg.max_samples);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const cv::Point& p = pixels[i];
    if (p.x < 2 || p.y < 2 || p.x >= Ih.cols - 2 || p.y >= Ih.rows - 2) continue;
    for (int k = 0; k < 8; ++k)
      ref_val[k] = e * (Ih.at<float>(p.y + kPattern[k][1], p.x + kPattern[k][0]) - host.b) + ref.b;
    const Vec3 Rx = R * cam.pinholeRay(p.x, p.y);
    double u0, v0, u1, v1;
    if (!proj(Rx, rho_lo, u0, v0) || !proj(Rx, rho_hi, u1, v1)) continue;
    const double len = std::hypot(u1 - u0, v1 - v0);
    out[i].line_px = len;
    if (len < cfg.min_line_px) continue;
    const int n = std::clamp(static_cast<int>(len / cfg.step_px) + 1, 2, cfg.max_samples);
    const auto energy = [&](double rho) {
      double u, v;
      if (!proj(Rx, rho, u, v) || !inside(u, v)) return std::numeric_limits<double>::infinity();
      double E = 0;
      for (int k = 0; k < 8; ++k) {
        const double r = sampleBilinear(Ir, u + kPattern[k][0], v + kPattern[k][1]) - ref_val[k];
        E += r * r;
      }
      return E;
    };
    // Inverse depth sampled uniformly in the pixel position along the line: interpolate ρ between
    // samples of the (monotonic) map ρ -> position by a fine uniform scan in ρ, which is close enough
    // for a scan step of half a pixel when the segment is short; long segments use more samples.
    double best = std::numeric_limits<double>::infinity(), second = best;
    int best_j = -1;
    for (int j = 0; j < n; ++j) {
      E[j] = energy(rho_lo + (rho_hi - rho_lo) * j / (n - 1));
      if (E[j] < best) best = E[j], best_j = j;
    }
    if (best_j < 0 || !std::isfinite(best)) continue;
    for (int j = 0; j < n; ++j)
      if (std::abs(j - best_j) > 2) second = std::min(second, E[j]);
    // Not unique: "<=" so that two exact matches (zero energy both) are refused as well.
    if (second <= cfg.uniqueness * best) continue;
    // Gauss-Newton on ρ from the best sample (numeric derivative of the residuals along the line).
    double rho = rho_lo + (rho_hi - rho_lo) * best_j / (n - 1);
    const double h = (rho_hi - rho_lo) / (n - 1) * 0.05;
    for (int it = 0; it < 5; ++it) {
      double u, v, up, vp;
      if (!proj(Rx, rho, u, v) || !proj(Rx, rho + h, up, vp) || !inside(u, v)) break;
      const double du = (up - u) / h, dv = (vp - v) / h;
      double Hs = 0, g = 0;
      for (int k = 0; k < 8; ++k) {
        double gx, gy;
        const double r = sampleBilinear(Ir, u + kPattern[k][0], v + kPattern[k][1], gx, gy) - ref_val[k];
        const double J = gx * du + gy * dv;
        Hs += J * J, g += J * r;
      }
      if (!(Hs > 0)) break;
      const double step = std::clamp(-g / Hs, -2 * h / 0.05, 2 * h / 0.05);
      const double rho_new = std::clamp(rho + step, rho_lo, rho_hi);
      if (!(energy(rho_new) < energy(rho))) break;
      rho = rho_new;
    }
    const double Eb = energy(rho);
    if (!std::isfinite(Eb) || std::sqrt(Eb / 8) > cfg.max_rms) continue;
    out[i].inv_depth = rho;
    out[i].rms = std::sqrt(Eb / 8);
  }
  return out;
}

}  // namespace eds
