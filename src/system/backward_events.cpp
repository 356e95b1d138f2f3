#include "system/backward_events.hpp"

#include <algorithm>
#include <cmath>

#include "system/event_frontend.hpp"

namespace eds {

std::pair<double, double> meanSpeed(const StampedPose& a, const StampedPose& b) {
  if (b.t <= a.t) return {0.0, 0.0};
  const SE3 move = a.T_w_c.inverse() * b.T_w_c;
  const double span = toSeconds(b.t - a.t);
  return {move.translation().norm() / span, move.so3().angle() / span};
}

BackwardPoses trackBackwards(const std::vector<EventFrame>& buffered, const BackwardPass& pass,
                             const CameraModel& pinhole, const OdometryConfig& cfg,
                             std::vector<OdometryFailure>& failures) {
  constexpr int kMaxRejected = 3;
  EventFrontend back(pinhole, cfg.events);
  back.setReference(*pass.ref, pass.T_w_kf);
  // A start other than the reference's own view (a frame's): the first solve begins there.
  if (pass.start.t != pass.ref->t) back.restartFrom(pass.start.T_w_c);
  StampedPose last = pass.start;
  BackwardPoses out;
  EventFrame ef;
  int rejected = 0;
  for (auto it = buffered.rbegin(); it != buffered.rend() && rejected < kMaxRejected; ++it) {
    if (it->t >= pass.start.t) continue;
    if (it->t < pass.t_min) break;
    ef.t = it->t, ef.t_first = it->t_first, ef.t_last = it->t_last;
    it->delta.convertTo(ef.delta, CV_32F);
    std::string why;
    const std::optional<SE3> T = back.track(ef, nullptr, &why);
    const SE3 s = T ? last.T_w_c.inverse() * *T : SE3();
    const double dt = kMaxSpeedup * toSeconds(last.t - ef.t);
    if (T && (s.translation().norm() > dt * pass.speed_t + cfg.buffered_gate_translation ||
              s.so3().angle() > dt * pass.speed_r + cfg.buffered_gate_rotation_deg * M_PI / 180.0))
      why = "faster than the frames around it";
    if (!why.empty()) {
      failures.push_back({ef.t, pass.what + ": " + why});
      ++rejected;
      continue;
    }
    rejected = 0;
    last = {ef.t, *T};
    out.poses.push_back(last);
    out.last_t.push_back(ef.t_last);
    out.correlations.push_back(back.lastCorrelation());
  }
  out.kf_id = back.referenceId();
  out.T_w_kf = back.T_w_kf();
  return out;
}

std::size_t trackEventsBackwards(const std::vector<EventFrame>& buffered, const BackwardPass& pass,
                                 const CameraModel& pinhole, const OdometryConfig& cfg, OdometryResult& res) {
  const BackwardPoses b = trackBackwards(buffered, pass, pinhole, cfg, res.failures);
  res.events_tracked += b.poses.size();
  for (std::size_t k = b.poses.size(); k-- > 0;) {
    res.events.push_back(b.poses[k]);
    res.event_last_t.push_back(b.last_t[k]);
    res.event_anchors.push_back({b.kf_id, b.T_w_kf.inverse() * b.poses[k].T_w_c});
    res.event_correlations.push_back(b.correlations[k]);
  }
  return b.poses.size();
}

std::size_t retrackEvents(const std::vector<EventFrame>& since, const StampedPose& before,
                          const StampedPose& frame, const Keyframe& ref, const SE3& T_w_kf,
                          const CameraModel& pinhole, const OdometryConfig& cfg, OdometryResult& res) {
  const auto [speed_t, speed_r] = meanSpeed(before, frame);
  const BackwardPass pass{&ref, T_w_kf, frame, before.t + 1, speed_t, speed_r, "event frame tracked again"};
  // A rejection here leaves the forward pose: no failure to list.
  std::vector<OdometryFailure> rejected;
  const BackwardPoses b = trackBackwards(since, pass, pinhole, cfg, rejected);
  const double gate_r = cfg.buffered_gate_rotation_deg * M_PI / 180.0;
  const double span = toSeconds(frame.t - before.t);
  std::size_t moved = 0, i = res.events.size();
  for (std::size_t k = 0; k < b.poses.size(); ++k) {  // newest first, as res.events from the end
    const StampedPose& p = b.poses[k];
    while (i > 0 && res.events[i - 1].t > p.t) --i;
    if (i == 0) break;
    if (res.events[i - 1].t != p.t) continue;
    const SE3& T_w_fwd = res.events[i - 1].T_w_c;
    const SE3 d = T_w_fwd.inverse() * p.T_w_c;
    SE3 T_w_c = p.T_w_c;
    if (d.translation().norm() <= cfg.buffered_gate_translation && d.so3().angle() <= gate_r)
      T_w_c = T_w_fwd * SE3::exp(std::clamp(toSeconds(p.t - before.t) / span, 0.0, 1.0) * d.log());
    else if (b.correlations[k] < res.event_correlations[i - 1] - kRetrackCorrelationMargin)
      continue;
    res.event_anchors[i - 1] = {b.kf_id, b.T_w_kf.inverse() * T_w_c};
    ++moved;
  }
  return moved;
}

}  // namespace eds
