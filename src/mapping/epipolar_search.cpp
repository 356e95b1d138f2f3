#include "mapping/epipolar_search.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

#include "core/image_sampling.hpp"
#include "core/parallel.hpp"

namespace eds {

namespace {
constexpr int kPattern[8][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0}, {0, 0}, {2, 0}, {-1, 1}, {0, 2}};

// The search of one host pixel along its line in the reference; what is shared by all pixels of one
// (host, reference) pair is set up once.
class LineSearch {
 public:
  LineSearch(const SearchFrame& host, const SearchFrame& ref, const CameraModel& cam, double rho_lo,
             double rho_hi, const EpipolarSearchConfig& cfg)
      : host_(host),
        ref_(ref),
        cam_(cam),
        Ih_(*host.image),
        Ir_(*ref.image),
        lo_(rho_lo),
        hi_(rho_hi),
        cfg_(cfg) {
    const SE3 T_r_h = ref.T_w_c.inverse() * host.T_w_c;
    R_ = T_r_h.rotationMatrix();
    t_ = T_r_h.translation();
    e_ = std::exp(ref.a - host.a);
    row_ = static_cast<std::ptrdiff_t>(Ir_.step1());
    for (int k = 0; k < 8; ++k) tap_[k] = kPattern[k][1] * row_ + kPattern[k][0];
  }

  // E: scratch of cfg.max_samples energies.
  EpipolarMatch match(const cv::Point& p, std::vector<double>& E) const;

 private:
  // Pixel in the reference of host pixel ray x at inverse depth rho: π(R x + rho t) (scaled by rho).
  bool proj(const Vec3& Rx, double rho, double& u, double& v) const {
    const Vec3 q = Rx + rho * t_;
    if (q.z() <= 1e-9) return false;
    u = cam_.fx * q.x() / q.z() + cam_.cx, v = cam_.fy * q.y() / q.z() + cam_.cy;
    return true;
  }
  bool inside(double u, double v) const { return u >= 3 && v >= 3 && u < Ir_.cols - 4 && v < Ir_.rows - 4; }
  double energy(const Vec3& Rx, const std::array<double, 8>& ref_val, double rho) const {
    double u, v;
    if (!proj(Rx, rho, u, v) || !inside(u, v)) return std::numeric_limits<double>::infinity();
    // The pattern's offsets are whole pixels, so every tap has the centre's bilinear fractions: this
    // is the scan's inner loop.
    const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
    const float ax = static_cast<float>(u - x0), ay = static_cast<float>(v - y0);
    const float* c = Ir_.ptr<float>(y0) + x0;
    double E = 0;
    for (int k = 0; k < 8; ++k) {
      const float* r0 = c + tap_[k];
      const float* r1 = r0 + row_;
      const float I = (1 - ay) * ((1 - ax) * r0[0] + ax * r0[1]) + ay * ((1 - ax) * r1[0] + ax * r1[1]);
      const double r = I - ref_val[k];
      E += r * r;
    }
    return E;
  }
  double refine(const Vec3& Rx, const std::array<double, 8>& ref_val, double rho, double h) const;

  const SearchFrame &host_, &ref_;
  const CameraModel& cam_;
  const cv::Mat &Ih_, &Ir_;
  double lo_, hi_;
  const EpipolarSearchConfig& cfg_;
  Mat3 R_;
  Vec3 t_;
  double e_ = 1;
  std::ptrdiff_t row_ = 0;               // floats per image row
  std::array<std::ptrdiff_t, 8> tap_{};  // each pattern pixel's offset from the centre, in floats
};

EpipolarMatch LineSearch::match(const cv::Point& p, std::vector<double>& E) const {
  EpipolarMatch out;
  if (p.x < 2 || p.y < 2 || p.x >= Ih_.cols - 2 || p.y >= Ih_.rows - 2) return out;
  std::array<double, 8> ref_val{};
  for (int k = 0; k < 8; ++k)
    ref_val[k] = e_ * (Ih_.at<float>(p.y + kPattern[k][1], p.x + kPattern[k][0]) - host_.b) + ref_.b;
  const Vec3 Rx = R_ * cam_.pinholeRay(p.x, p.y);
  double u0, v0, u1, v1;
  if (!proj(Rx, lo_, u0, v0) || !proj(Rx, hi_, u1, v1)) return out;
  const double len = std::hypot(u1 - u0, v1 - v0);
  out.line_px = len;
  if (len < cfg_.min_line_px) return out;
  const int n = std::clamp(static_cast<int>(len / cfg_.step_px) + 1, 2, cfg_.max_samples);
  // Inverse depth sampled uniformly in the pixel position along the line: interpolate ρ between
  // samples of the (monotonic) map ρ -> position by a fine uniform scan in ρ, which is close enough
  // for a scan step of half a pixel when the segment is short; long segments use more samples.
  double best = std::numeric_limits<double>::infinity(), second = best;
  int best_j = -1;
  for (int j = 0; j < n; ++j) {
    E[j] = energy(Rx, ref_val, lo_ + (hi_ - lo_) * j / (n - 1));
    if (E[j] < best) best = E[j], best_j = j;
  }
  if (best_j < 0 || !std::isfinite(best)) return out;
  for (int j = 0; j < n; ++j)
    if (std::abs(j - best_j) > 2) second = std::min(second, E[j]);
  // Not unique: "<=" so that two exact matches (zero energy both) are refused as well.
  if (second <= cfg_.uniqueness * best) return out;
  const double rho = refine(Rx, ref_val, lo_ + (hi_ - lo_) * best_j / (n - 1), (hi_ - lo_) / (n - 1) * 0.05);
  const double Eb = energy(Rx, ref_val, rho);
  if (!std::isfinite(Eb) || std::sqrt(Eb / 8) > cfg_.max_rms) return out;
  out.inv_depth = rho;
  out.rms = std::sqrt(Eb / 8);
  return out;
}

// Gauss-Newton on ρ from the best sample (numeric derivative of the residuals along the line, step h).
double LineSearch::refine(const Vec3& Rx, const std::array<double, 8>& ref_val, double rho, double h) const {
  for (int it = 0; it < 5; ++it) {
    double u, v, up, vp;
    if (!proj(Rx, rho, u, v) || !proj(Rx, rho + h, up, vp) || !inside(u, v)) break;
    const double du = (up - u) / h, dv = (vp - v) / h;
    double Hs = 0, g = 0;
    for (int k = 0; k < 8; ++k) {
      double gx, gy;
      const double r = sampleBilinear(Ir_, u + kPattern[k][0], v + kPattern[k][1], gx, gy) - ref_val[k];
      const double J = gx * du + gy * dv;
      Hs += J * J, g += J * r;
    }
    if (!(Hs > 0)) break;
    const double step = std::clamp(-g / Hs, -2 * h / 0.05, 2 * h / 0.05);
    const double rho_new = std::clamp(rho + step, lo_, hi_);
    if (!(energy(Rx, ref_val, rho_new) < energy(Rx, ref_val, rho))) break;
    rho = rho_new;
  }
  return rho;
}

}  // namespace

std::vector<EpipolarMatch> epipolarSearch(const SearchFrame& host, const SearchFrame& ref,
                                          const CameraModel& cam, const std::vector<cv::Point>& pixels,
                                          double rho_lo, double rho_hi, const EpipolarSearchConfig& cfg) {
  std::vector<EpipolarMatch> out(pixels.size());
  const LineSearch search(host, ref, cam, rho_lo, rho_hi, cfg);
  // Each pixel's search is independent: chunks in parallel, each with its own scratch.
  forEachChunk(pixels.size(), [&](int, std::size_t begin, std::size_t end) {
    std::vector<double> E(cfg.max_samples);
    for (std::size_t i = begin; i < end; ++i) out[i] = search.match(pixels[i], E);
  });
  return out;
}

}  // namespace eds
