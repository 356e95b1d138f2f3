#pragma once
// Small helpers the runs share: wall-clock timing of stages and their summary statistics for
// summary.json, and a pose looked up in a trajectory by time.
#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "io/trajectory_io.hpp"

namespace eds {

using Clock = std::chrono::steady_clock;

inline double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// median, p95, mean and max of per-item timings (null when there are none).
inline nlohmann::json timingStats(std::vector<double> v) {
  if (v.empty()) return nullptr;
  std::sort(v.begin(), v.end());
  const auto pct = [&](double q) {
    return v[std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5))];
  };
  double sum = 0;
  for (double x : v) sum += x;
  return {{"median", pct(0.5)}, {"p95", pct(0.95)}, {"mean", sum / v.size()}, {"max", v.back()}};
}

// Pose at time t from a trajectory sorted by time: interpolated inside, the nearest end outside.
inline SE3 poseAt(const Trajectory& traj, TimeNs t) {
  if (traj.empty()) throw std::logic_error("poseAt on an empty trajectory");
  if (t <= traj.front().t) return traj.front().T_w_c;
  if (t >= traj.back().t) return traj.back().T_w_c;
  const auto it =
      std::lower_bound(traj.begin(), traj.end(), t, [](const StampedPose& s, TimeNs tt) { return s.t < tt; });
  const StampedPose& b = *it;
  const StampedPose& a = *(it - 1);
  return interpolate(a.T_w_c, b.T_w_c, static_cast<double>(t - a.t) / static_cast<double>(b.t - a.t));
}

}  // namespace eds
