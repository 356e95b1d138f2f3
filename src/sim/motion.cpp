#include "sim/motion.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace eds::sim {

Motion::Motion(Trajectory samples) : samples_(std::move(samples)) {
  if (samples_.size() < 2) throw std::invalid_argument("Motion: need at least 2 poses");
  for (std::size_t i = 1; i < samples_.size(); ++i)
    if (samples_[i].t < samples_[i - 1].t)
      throw std::invalid_argument("Motion: timestamps must not decrease");
  if (samples_.front().t == samples_.back().t) throw std::invalid_argument("Motion: zero time span");
}

SE3 Motion::pose(TimeNs t) const {
  if (t <= samples_.front().t) return samples_.front().T_w_c;
  if (t >= samples_.back().t) return samples_.back().T_w_c;
  // First sample after t; its predecessor is at or before t, so the interval is never empty.
  const auto b = std::upper_bound(samples_.begin(), samples_.end(), t,
                                  [](TimeNs tt, const StampedPose& p) { return tt < p.t; });
  const auto a = b - 1;
  const double s = static_cast<double>(t - a->t) / static_cast<double>(b->t - a->t);
  return interpolate(a->T_w_c, b->T_w_c, s);
}

// Smoothing is a Gaussian-weighted local *linear* fit around each sample, evaluated at the sample.
// With symmetric neighbours (uniform sampling, away from the ends) this is exactly the Gaussian
// average; unlike the plain average it leaves constant velocity untouched at the ends of the
// trajectory and across uneven sampling. Each neighbour is also weighted by the time it represents
// (half the span to its neighbours), so densely sampled stretches do not dominate.
Trajectory smoothTrajectory(const Trajectory& traj, double sigma_s) {
  if (!(sigma_s > 0) || traj.size() < 3) return traj;
  const std::size_t n = traj.size();
  std::vector<double> t(n), span(n);
  for (std::size_t i = 0; i < n; ++i) t[i] = toSeconds(traj[i].t - traj.front().t);
  for (std::size_t i = 0; i < n; ++i)
    span[i] = std::max(0.5 * (t[std::min(i + 1, n - 1)] - t[i == 0 ? 0 : i - 1]), 1e-12);
  const double reach = 3.0 * sigma_s, inv2s2 = 1.0 / (2.0 * sigma_s * sigma_s);

  Trajectory out(n);
  std::size_t lo = 0, hi = 0;  // window [lo, hi)
  for (std::size_t i = 0; i < n; ++i) {
    while (t[i] - t[lo] > reach) ++lo;
    while (hi < n && t[hi] - t[i] <= reach) ++hi;
    const SE3& Ti = traj[i].T_w_c;
    const SO3 R_inv = Ti.so3().inverse();
    double S0 = 0, S1 = 0, S2 = 0;
    Vec3 P0 = Vec3::Zero(), P1 = Vec3::Zero(), W0 = Vec3::Zero(), W1 = Vec3::Zero();
    for (std::size_t j = lo; j < hi; ++j) {
      const double x = t[j] - t[i];
      const double w = std::exp(-x * x * inv2s2) * span[j];
      // Offsets from sample i, in position and in the tangent space of R_i.
      const Vec3 dp = traj[j].T_w_c.translation() - Ti.translation();
      const Vec3 dr = (R_inv * traj[j].T_w_c.so3()).log();
      S0 += w, S1 += w * x, S2 += w * x * x;
      P0 += w * dp, P1 += w * x * dp;
      W0 += w * dr, W1 += w * x * dr;
    }
    // Intercept of the weighted line fit; a lone sample (a gap) keeps its value.
    const double det = S0 * S2 - S1 * S1;
    Vec3 dp, dr;
    if (det > 1e-9 * S0 * S2 && S2 > 0) {
      dp = (S2 * P0 - S1 * P1) / det;
      dr = (S2 * W0 - S1 * W1) / det;
    } else {
      dp = P0 / S0;
      dr = W0 / S0;
    }
    Quat q = (Ti.so3() * SO3::exp(dr)).quaternion();
    // Same hemisphere as the previous output, so files and slerp see no sign flips.
    if (i > 0 && q.dot(out[i - 1].T_w_c.quaternion()) < 0) q.coeffs() = -q.coeffs();
    out[i] = {traj[i].t, SE3(q, Ti.translation() + dp)};
  }
  return out;
}

// t_start is counted from the trajectory's first pose, so files with large time offsets (DSEC's
// ~1.5e9 s) are as easy to cut as ECD's.
Trajectory cutTrajectory(const Trajectory& traj, double t_start_s, double duration_s,
                         const std::string& source) {
  if (!std::isfinite(t_start_s) || !std::isfinite(duration_s) || t_start_s < 0 || duration_s <= 0)
    throw InputError(source, "the window must have t_start >= 0 and duration > 0");
  if (traj.size() < 2) throw InputError(source, "trajectory has fewer than 2 poses");
  const TimeNs t0 = traj.front().t + fromSeconds(t_start_s);
  const TimeNs t1 = t0 + fromSeconds(duration_s);
  if (t1 > traj.back().t) {
    std::ostringstream msg;
    msg << "trajectory is too short: it spans " << toSeconds(traj.back().t - traj.front().t)
        << " s, the window asks for [" << t_start_s << ", " << t_start_s + duration_s << "] s from its start";
    throw InputError(source, msg.str());
  }
  std::optional<Motion> motion;
  try {
    motion.emplace(traj);
  } catch (const std::invalid_argument& e) {
    throw InputError(source, e.what());
  }
  Trajectory out;
  out.push_back({0, motion->pose(t0)});
  for (const StampedPose& p : traj)
    if (p.t > t0 && p.t < t1) out.push_back({p.t - t0, p.T_w_c});
  out.push_back({t1 - t0, motion->pose(t1)});
  return out;
}

namespace {

// One smooth random signal: a sum of sinusoids minus their value at t = 0, so it starts at 0 and
// stays within +-2 * (sum of amplitudes).
struct Waves {
  std::array<double, 3> amp{}, freq{}, phase{};
  int count = 0;
  double operator()(double t) const {
    double s = 0;
    for (int k = 0; k < count; ++k)
      s += amp[k] * (std::sin(2 * std::numbers::pi * freq[k] * t + phase[k]) - std::sin(phase[k]));
    return s;
  }
};

class WaveMaker {
 public:
  explicit WaveMaker(std::uint64_t seed) : gen_(seed) {}
  // One sinusoid per frequency band; amplitudes random, scaled so that they sum to `total`.
  Waves make(const std::vector<std::pair<double, double>>& bands, double total) {
    Waves w;
    w.count = static_cast<int>(bands.size());
    double sum = 0;
    for (int k = 0; k < w.count; ++k) {
      w.freq[k] = uniform(bands[k].first, bands[k].second);
      w.phase[k] = uniform(0, 2 * std::numbers::pi);
      w.amp[k] = uniform(0.5, 1.0);
      sum += w.amp[k];
    }
    for (int k = 0; k < w.count; ++k) w.amp[k] *= total / sum;
    return w;
  }

 private:
  // From raw bits: std::uniform_real_distribution is not the same in every standard library.
  double uniform(double a, double b) { return a + (b - a) * static_cast<double>(gen_() >> 11) * 0x1.0p-53; }
  std::mt19937_64 gen_;
};

}  // namespace

Trajectory handheldMotion(double duration_s, std::uint64_t seed, double rate_hz) {
  if (!(duration_s > 0) || !(rate_hz > 0))
    throw std::invalid_argument("handheldMotion: duration and rate must be > 0");
  WaveMaker maker(seed);
  constexpr double kDeg = std::numbers::pi / 180.0;
  // Rotation (rotation vector in the start camera's axes: x pitch, y yaw, z roll). Each axis is
  // bounded by 2 * total, so yaw and pitch stay within ~13 deg and the camera keeps facing +z; with
  // components up to 2 Hz the peak rates are ~30-60 deg/s, a lively hand-held shake.
  const std::vector<std::pair<double, double>> rot_bands = {{0.3, 0.6}, {0.6, 1.1}, {1.1, 2.0}};
  const Waves pitch = maker.make(rot_bands, 5.5 * kDeg);
  const Waves yaw = maker.make(rot_bands, 6.5 * kDeg);
  const Waves roll = maker.make(rot_bands, 4.0 * kDeg);
  // Translation: slow, +-10-16 cm, least along the optical axis (near objects stay clear).
  const std::vector<std::pair<double, double>> pos_bands = {{0.2, 0.5}, {0.5, 1.0}};
  const Waves px = maker.make(pos_bands, 0.08);
  const Waves py = maker.make(pos_bands, 0.06);
  const Waves pz = maker.make(pos_bands, 0.05);

  const auto n = static_cast<std::size_t>(std::ceil(duration_s * rate_hz - 1e-9)) + 1;
  Trajectory traj;
  traj.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = std::min(static_cast<double>(k) / rate_hz, duration_s);
    const SO3 R = SO3::exp(Vec3(pitch(t), yaw(t), roll(t)));
    traj.push_back({fromSeconds(t), SE3(R, Vec3(px(t), py(t), pz(t)))});
  }
  return traj;
}

}  // namespace eds::sim
