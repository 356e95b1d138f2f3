#include "eval/rpe.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>

namespace eds::eval {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// Cumulative path length along the positions, starting at 0.
std::vector<double> distanceFromStart(const std::vector<Vec3>& p) {
  std::vector<double> d(p.size(), 0.0);
  for (std::size_t i = 1; i < p.size(); ++i) d[i] = d[i - 1] + (p[i] - p[i - 1]).norm();
  return d;
}

// For each start pose, the first index whose accumulated length is closest to start + dist (strictly
// closer than max_diff). Binary search replaces the toolbox's quadratic scan with the same result:
// |acc[i] - target| is non-increasing left of the target and non-decreasing right of it.
// As in the toolbox, start poses without a partner are skipped and the list is not re-indexed.
std::vector<std::size_t> comparisonIndices(const std::vector<double>& acc, double dist, double max_diff) {
  std::vector<std::size_t> out;
  for (std::size_t idx = 0; idx < acc.size(); ++idx) {
    const double target = acc[idx] + dist;
    const auto diff = [&](std::size_t i) { return std::abs(acc[i] - target); };
    const std::size_t right = static_cast<std::size_t>(
        std::lower_bound(acc.begin() + static_cast<std::ptrdiff_t>(idx), acc.end(), target) - acc.begin());
    double best = std::numeric_limits<double>::infinity();
    if (right < acc.size()) best = diff(right);
    if (right > idx) best = std::min(best, diff(right - 1));
    if (!(best < max_diff)) continue;
    // The scan keeps the first index reaching the minimum: search the left part for it.
    std::size_t lo = idx, hi = right;  // first i in [idx, right) with diff(i) <= best, else right
    while (lo < hi) {
      const std::size_t mid = lo + (hi - lo) / 2;
      if (diff(mid) <= best)
        hi = mid;
      else
        lo = mid + 1;
    }
    out.push_back(lo);
  }
  return out;
}

Eigen::Matrix4d rigid(const Quat& q, const Vec3& p) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = q.toRotationMatrix();
  T.topRightCorner<3, 1>() = p;
  return T;
}

// Yaw and (pitch, roll) of a rotation in the toolbox's 'rzyx' Euler convention.
void yawPitchRoll(const Mat3& M, double& yaw, double& pitch, double& roll) {
  const double cy = std::sqrt(M(0, 0) * M(0, 0) + M(1, 0) * M(1, 0));
  if (cy > 4.0 * std::numeric_limits<double>::epsilon()) {
    roll = std::atan2(M(2, 1), M(2, 2));
    pitch = std::atan2(-M(2, 0), cy);
    yaw = std::atan2(M(1, 0), M(0, 0));
  } else {
    roll = std::atan2(-M(1, 2), M(1, 1));
    pitch = std::atan2(-M(2, 0), cy);
    yaw = 0.0;
  }
}

// Angle from the trace, clipped, in degrees: the toolbox's compute_angle.
double traceAngleDeg(const Mat3& R) {
  return std::acos(std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0)) * kRadToDeg;
}

}  // namespace

std::string rpeDistanceTag(double distance) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%3.1f", distance);
  std::string s(buf);
  std::replace(s.begin(), s.end(), '.', '_');
  return s;
}

nlohmann::json toJson(const std::vector<RpeResult>& results) {
  nlohmann::json out = nlohmann::json::array();
  for (const RpeResult& r : results)
    out.push_back({{"distance", r.distance},
                   {"trans", toJson(r.trans)},
                   {"trans_perc", toJson(r.trans_perc)},
                   {"rot", toJson(r.rot)},
                   {"yaw", toJson(r.yaw)},
                   {"gravity", toJson(r.gravity)},
                   {"rot_deg_per_m", toJson(r.rot_deg_per_m)}});
  return out;
}

std::vector<RpeResult> evaluateRpe(const Trajectory& est, const Trajectory& gt, const AteResult& ate,
                                   const EvalConfig& cfg, const RpeConfig& rpe) {
  // Total length: raw ground truth (file order) inside the window.
  std::vector<Vec3> raw;
  for (const StampedPose& g : gt)
    if (!cfg.window || cfg.window->contains(g.t)) raw.push_back(g.T_w_c.translation());
  const double total = raw.empty() ? 0.0 : distanceFromStart(raw).back();

  const std::size_t n = ate.pairs.size();
  std::vector<Vec3> p_gt(n);
  std::vector<Eigen::Matrix4d> T_es(n), T_gt(n);
  for (std::size_t i = 0; i < n; ++i) {
    const SE3& G = gt[ate.pairs[i].gt].T_w_c;
    const SE3& E = est[ate.pairs[i].est].T_w_c;
    p_gt[i] = G.translation();
    T_gt[i] = rigid(G.quaternion(), G.translation());
    T_es[i] = rigid(E.quaternion(), E.translation());
  }
  const std::vector<double> acc = distanceFromStart(p_gt);

  std::vector<RpeResult> results;
  for (const double fraction : rpe.length_fractions) {
    RpeResult r;
    r.distance = std::trunc(fraction * total * 100.0) / 100.0;
    const std::vector<std::size_t> comparisons =
        comparisonIndices(acc, r.distance, rpe.max_length_diff_ratio * r.distance);
    std::vector<double> trans, trans_perc, rot, yaw, gravity, rot_per_m;
    if (comparisons.size() >= 2 && r.distance > 0.0) {
      for (std::size_t k = 0; k < comparisons.size(); ++k) {
        const std::size_t c = comparisons[k];  // paired with k, not with its start index (toolbox)
        Eigen::Matrix4d T_c1_c2 = T_es[k].inverse() * T_es[c];
        T_c1_c2.topRightCorner<3, 1>() *= ate.transform.s;
        const Eigen::Matrix4d T_m1_m2 = T_gt[k].inverse() * T_gt[c];
        const Eigen::Matrix4d E_c2 = T_m1_m2.inverse() * T_c1_c2;
        Eigen::Matrix4d R_c2 = Eigen::Matrix4d::Identity();
        R_c2.topLeftCorner<3, 3>() = T_es[c].topLeftCorner<3, 3>();
        const Eigen::Matrix4d E = R_c2 * E_c2 * R_c2.inverse();
        const double tn = E.topRightCorner<3, 1>().norm();
        double ey = 0, ep = 0, er = 0;
        yawPitchRoll(E.topLeftCorner<3, 3>(), ey, ep, er);
        const double angle = traceAngleDeg(E.topLeftCorner<3, 3>());
        trans.push_back(tn);
        trans_perc.push_back(tn / r.distance * 100.0);
        rot.push_back(angle);
        yaw.push_back(std::abs(ey) * kRadToDeg);
        gravity.push_back(std::sqrt(ep * ep + er * er) * kRadToDeg);
        rot_per_m.push_back(angle / r.distance);
      }
    }
    r.trans = computeStats(trans);
    r.trans_perc = computeStats(trans_perc);
    r.rot = computeStats(rot);
    r.yaw = computeStats(yaw);
    r.gravity = computeStats(gravity);
    r.rot_deg_per_m = computeStats(rot_per_m);
    results.push_back(r);
  }
  return results;
}

}  // namespace eds::eval
