#include "system/backward_events.hpp"

#include <cmath>

#include "system/event_frontend.hpp"

namespace eds {

std::size_t trackEventsBackwards(const std::vector<EventFrame>& buffered, const BackwardPass& pass,
                                 const CameraModel& pinhole, const OdometryConfig& cfg, OdometryResult& res) {
  constexpr int kMaxRejected = 3;
  EventFrontend back(pinhole, cfg.events);
  back.setReference(*pass.ref, pass.T_w_kf);
  StampedPose last = pass.start;
  Trajectory poses;
  std::vector<TimeNs> last_t;
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
      res.failures.push_back({ef.t, pass.what + ": " + why});
      ++rejected;
      continue;
    }
    rejected = 0;
    last = {ef.t, *T};
    poses.push_back(last);
    last_t.push_back(ef.t_last);
  }
  res.events_tracked += poses.size();
  for (std::size_t k = poses.size(); k-- > 0;) {
    res.events.push_back(poses[k]);
    res.event_last_t.push_back(last_t[k]);
    res.event_anchors.push_back({back.referenceId(), back.T_w_kf().inverse() * poses[k].T_w_c});
  }
  return poses.size();
}

}  // namespace eds
