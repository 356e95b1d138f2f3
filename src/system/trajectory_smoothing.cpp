#include "system/trajectory_smoothing.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <stdexcept>

#include "system/run_stats.hpp"

namespace eds {

Trajectory smoothPoses(const Trajectory& traj, double half_window_s) {
  Trajectory out = traj;
  if (!(half_window_s > 0)) return out;
  if (!std::is_sorted(traj.begin(), traj.end(),
                      [](const StampedPose& a, const StampedPose& b) { return a.t < b.t; }))
    throw std::invalid_argument("smoothPoses: poses out of time order");
  const TimeNs half = fromSeconds(half_window_s);
  std::size_t lo = 0, hi = 0;  // the window [lo, hi) of pose i
  for (std::size_t i = 0; i < traj.size(); ++i) {
    while (traj[lo].t < traj[i].t - half) ++lo;
    while (hi < traj.size() && traj[hi].t <= traj[i].t + half) ++hi;
    if (hi - lo < 4) continue;  // a parabola through three points is no smoothing
    // p(s) = a + b s + c s^2 with s = dt / half_window (conditioning); the fit's value at s = 0 is a.
    // Right-hand sides: x, y, z of the position, then the rotation vector from pose i's orientation
    // (small within the window, so the fit in the tangent space at pose i is nearly a fit on SO(3)).
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Matrix<double, 3, 6> B = Eigen::Matrix<double, 3, 6>::Zero();
    const SO3 R_i_inv = traj[i].T_w_c.so3().inverse();
    for (std::size_t k = lo; k < hi; ++k) {
      const double s = toSeconds(traj[k].t - traj[i].t) / half_window_s;
      const Eigen::Vector3d basis(1, s, s * s);
      Eigen::Matrix<double, 6, 1> rhs;
      rhs << traj[k].T_w_c.translation(), (R_i_inv * traj[k].T_w_c.so3()).log();
      A.noalias() += basis * basis.transpose();
      B.noalias() += basis * rhs.transpose();
    }
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
    if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-9)) continue;  // all poses at one time
    const Eigen::Matrix<double, 3, 6> coef = ldlt.solve(B);
    const Vec3 dw = coef.block<1, 3>(0, 3).transpose();
    out[i].T_w_c = SE3(traj[i].T_w_c.so3() * SO3::exp(dw), coef.block<1, 3>(0, 0).transpose());
  }
  return out;
}

namespace {

struct Offset {
  Vec3 dp;
  Quat dq;  // R_frame R_event^-1
};

Offset offsetAt(const Trajectory& events, const StampedPose& frame) {
  const SE3 T_e = poseAt(events, frame.t);
  return {frame.T_w_c.translation() - T_e.translation(),
          frame.T_w_c.quaternion() * T_e.quaternion().conjugate()};
}

}  // namespace

Trajectory anchorToFrames(const Trajectory& events, const Trajectory& frames, TimeNs max_gap,
                          const std::vector<TimeNs>& breaks) {
  Trajectory out = events;
  if (events.size() < 2) return out;
  std::size_t k = 0;  // frames[k] is the first frame at or after the pose
  for (StampedPose& p : out) {
    while (k < frames.size() && frames[k].t < p.t) ++k;
    if (k == frames.size()) continue;
    // A pose at a frame's time takes that frame's offset alone.
    const StampedPose& b = frames[k];
    const StampedPose& a = b.t == p.t || k == 0 ? b : frames[k - 1];
    if (a.t > p.t) continue;  // before the first frame
    if (b.t - a.t > max_gap || a.t < events.front().t || b.t > events.back().t) continue;
    if (std::any_of(breaks.begin(), breaks.end(), [&](TimeNs t) { return t > a.t && t <= b.t; })) continue;
    const Offset oa = offsetAt(events, a), ob = offsetAt(events, b);
    const double w = b.t > a.t ? static_cast<double>(p.t - a.t) / static_cast<double>(b.t - a.t) : 0.0;
    const Quat dq = oa.dq.slerp(w, ob.dq);
    p.T_w_c = SE3(dq * p.T_w_c.quaternion(), p.T_w_c.translation() + (1 - w) * oa.dp + w * ob.dp);
  }
  return out;
}

}  // namespace eds
