#include "system/buffered_gate.hpp"

#include <algorithm>

#include "system/backward_events.hpp"
#include "system/run_stats.hpp"

namespace eds {

BufferedEventGate::BufferedEventGate(const Trajectory& frames, TimeNs t, const StampedPose& last,
                                     double margin_t, double margin_r)
    : last_(last), T_interp_(poseAt(frames, t)) {
  const auto it = std::lower_bound(frames.begin(), frames.end(), t,
                                   [](const StampedPose& p, TimeNs tt) { return p.t < tt; });
  const SE3& A = it == frames.begin() ? it->T_w_c : (it - 1)->T_w_c;
  const SE3& B = it == frames.end() ? (it - 1)->T_w_c : it->T_w_c;
  const SE3 AB = A.inverse() * B;
  const double ab_t = AB.translation().norm(), ab_r = AB.so3().angle();
  // Far from the interpolation: more than half the motion between the two frames, plus the margin.
  max_t_ = 0.5 * ab_t + margin_t, max_r_ = 0.5 * ab_r + margin_r;
  step_t_ = near_t_ = margin_t, step_r_ = near_r_ = margin_r;
  if (it == frames.begin() || it == frames.end()) return;
  before_ = &*(it - 1), after_ = &*it;
  if (before_->t > last_.t) last_ = *before_;
  const double span = toSeconds(after_->t - before_->t);
  if (!(span > 0)) return;
  // Frames a second apart leave the first bound wide, and a wrong minimum is a jump: no faster than
  // kMaxSpeedup times the frames' mean speed from the last accepted pose.
  const double f = kMaxSpeedup * toSeconds(t - last_.t) / span;
  step_t_ += f * ab_t, step_r_ += f * ab_r;
  // A camera that swings between frames far apart strays from their interpolation by more than half
  // their motion: such a pose passes within the same speed bound of the nearer frame.
  const bool a_nearer = t - before_->t <= after_->t - t;
  T_near_ = a_nearer ? A : B;
  const double g = kMaxSpeedup * toSeconds(a_nearer ? t - before_->t : after_->t - t) / span;
  near_t_ += g * ab_t, near_r_ += g * ab_r;
}

bool BufferedEventGate::accepts(const SE3& T_w_c) const {
  const SE3 d = T_interp_.inverse() * T_w_c;
  const bool interpolated = d.translation().norm() <= max_t_ && d.so3().angle() <= max_r_;
  if (!before_) return interpolated;
  const SE3 n = T_near_.inverse() * T_w_c, s = last_.T_w_c.inverse() * T_w_c;
  const bool near = n.translation().norm() <= near_t_ && n.so3().angle() <= near_r_;
  return (interpolated || near) && s.translation().norm() <= step_t_ && s.so3().angle() <= step_r_;
}

}  // namespace eds
