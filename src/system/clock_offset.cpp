#include "system/clock_offset.hpp"

#include <cmath>
#include <vector>

#include "system/run_stats.hpp"

namespace eds {

namespace {

// RMS of the rotation angle between each frame pose and the event trajectory at the frame's time plus
// `offset`; frames too near the event trajectory's ends for the largest offset are left out.
double rotationRmsDeg(const Trajectory& frames, const Trajectory& events, TimeNs offset, TimeNs margin) {
  double sum = 0;
  std::size_t n = 0;
  for (const StampedPose& f : frames) {
    if (f.t < events.front().t + margin || f.t > events.back().t - margin) continue;
    const SE3 T_e = poseAt(events, f.t + offset);
    const double angle = (f.T_w_c.so3().inverse() * T_e.so3()).log().norm();
    sum += angle * angle;
    ++n;
  }
  return n > 0 ? std::sqrt(sum / static_cast<double>(n)) * 180.0 / M_PI : 0.0;
}

}  // namespace

ClockOffsetEstimate estimateEventClockOffset(const Trajectory& frames, const Trajectory& events) {
  ClockOffsetEstimate e;
  constexpr TimeNs kRange = 10'000'000, kStep = 100'000;  // +-10 ms in 0.1 ms steps
  if (frames.size() < 10 || events.size() < 10) return e;
  std::size_t inside = 0;
  for (const StampedPose& f : frames)
    inside += f.t >= events.front().t + kRange && f.t <= events.back().t - kRange;
  if (inside < 10) return e;
  e.rms_deg_at_zero = rotationRmsDeg(frames, events, 0, kRange);
  e.rms_deg_at_best = e.rms_deg_at_zero;
  for (TimeNs d = -kRange; d <= kRange; d += kStep) {
    const double rms = rotationRmsDeg(frames, events, d, kRange);
    if (rms < e.rms_deg_at_best) e.rms_deg_at_best = rms, e.offset_ms = static_cast<double>(d) * 1e-6;
  }
  e.valid = e.rms_deg_at_zero > 0;
  return e;
}

}  // namespace eds
