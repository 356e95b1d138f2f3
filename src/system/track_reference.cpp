#include "system/track_reference.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/undistorter.hpp"
#include "frontend/event_packets.hpp"
#include "frontend/frame_tracker.hpp"
#include "system/event_frontend.hpp"
#include "system/run_stats.hpp"

namespace eds {

namespace {

void checkSameCamera(const CameraModel& a, const CameraModel& b, const std::string& source) {
  const auto close = [](double x, double y) { return std::abs(x - y) <= 1e-6 * std::max(1.0, std::abs(y)); };
  if (a.width != b.width || a.height != b.height || !close(a.fx, b.fx) || !close(a.fy, b.fy) ||
      !close(a.cx, b.cx) || !close(a.cy, b.cy))
    throw InputError(source,
                     "the run's camera differs from the sequence's (a reference map holds only for the "
                     "camera it was made with; pass the same --calib to both)");
}

// Index of the keyframe nearest in time to t (keyframes in time order).
std::size_t nearestKeyframe(const std::vector<Keyframe>& kfs, TimeNs t) {
  const auto it =
      std::lower_bound(kfs.begin(), kfs.end(), t, [](const Keyframe& k, TimeNs v) { return k.t < v; });
  if (it == kfs.begin()) return 0;
  if (it == kfs.end()) return kfs.size() - 1;
  const auto i = static_cast<std::size_t>(it - kfs.begin());
  return t - kfs[i - 1].t <= kfs[i].t - t ? i - 1 : i;
}

}  // namespace

TrackOnlyResult trackAgainstReference(const Sequence& seq, const ReferenceRun& ref, const OdometryConfig& cfg,
                                      bool use_frames) {
  const auto wall0 = Clock::now();
  cfg.event_frame.validate();
  if (!seq.hasEvents()) throw InputError((seq.dir() / "events.txt").string(), "no events to track");
  const Undistorter und(seq.camera());
  checkSameCamera(ref.pinhole, und.pinhole(), "keyframes/camera.txt");
  TrackOnlyResult res;
  std::size_t current = std::numeric_limits<std::size_t>::max();  // the event front-end's keyframe
  EventFrontend front(und.pinhole(), cfg.events);
  FrameTracker frames(und.pinhole(), cfg.frame_tracker);
  std::size_t next_frame = 0, frame_kf = std::numeric_limits<std::size_t>::max();
  SE3 T_w_last;  // the newest pose (event frame or frame)
  // Frames, where the sequence has them, are aligned to the keyframe nearest in time (seeded by the
  // newest pose) and correct the event front-end, whose motion prior then holds what one event
  // frame resolves least (as in eds run).
  const auto frameUpTo = [&](TimeNs t) {
    for (; next_frame < seq.frames().size() && seq.frames()[next_frame].t <= t; ++next_frame) {
      const TimeNs tf = seq.frames()[next_frame].t;
      const std::size_t k = nearestKeyframe(ref.keyframes, tf);
      if (current == std::numeric_limits<std::size_t>::max()) T_w_last = ref.keyframes[k].T_w_kf;
      if (k != frame_kf) frames.setKeyframe(ref.keyframes[k]), frame_kf = k;
      cv::Mat img;
      und.undistortImage(seq.loadFrame(next_frame)).convertTo(img, CV_32F, 1.0 / 255.0);
      SE3 T_f_kf = T_w_last.inverse() * ref.keyframes[k].T_w_kf;
      double alpha = 1.0, beta = 0.0;
      const auto t0 = Clock::now();
      const FrameTrackResult fr = frames.track(img, T_f_kf, alpha, beta);
      res.frame_track_ms.push_back(msSince(t0));
      if (!fr.ok) {
        res.failures.push_back({tf, "frame alignment failed (rmse " + std::to_string(fr.rmse) + ")"});
        continue;
      }
      T_w_last = ref.keyframes[k].T_w_kf * T_f_kf.inverse();
      front.correct(tf, T_w_last);
    }
  };
  EventFrameBuilder builder(und, cfg.event_frame);
  auto src = seq.openEvents();
  EventPacketStream packets(*src, cfg.event_frame);
  const EventArray* events = nullptr;
  std::size_t begin = 0;
  EventFrame ef;
  TimeNs t_first = -1, t_end = std::numeric_limits<TimeNs>::max();
  while (packets.next(events, begin)) {
    auto t0 = Clock::now();
    builder.build(*events, begin, ef, packets.base());
    res.build_ms.push_back(msSince(t0));
    if (t_first < 0) {
      t_first = ef.t;
      if (cfg.duration_s > 0) t_end = t_first + fromSeconds(cfg.duration_s);
    }
    if (ef.t > t_end) break;
    ++res.event_frames;
    res.sequence_s = toSeconds(ef.t - t_first);
    const std::size_t k = nearestKeyframe(ref.keyframes, ef.t);
    if (k != current) {
      front.setReference(ref.keyframes[k], ref.keyframes[k].T_w_kf);
      current = k;
      ++res.keyframes;
    }
    if (use_frames) frameUpTo(ef.t);
    t0 = Clock::now();
    std::string why;
    const std::optional<SE3> T_w_ef = front.track(ef, nullptr, &why);
    res.track_ms.push_back(msSince(t0));
    if (!T_w_ef) {
      res.failures.push_back({ef.t, "event frame: " + why});
      continue;
    }
    ++res.tracked;
    T_w_last = *T_w_ef;
    res.trajectory.push_back({ef.t, *T_w_ef});
    res.correlations.push_back(front.lastCorrelation());
  }
  if (res.event_frames == 0)
    throw InputError(seq.eventsFile().string(),
                     "not one event frame of " + std::to_string(cfg.event_frame.num_events) + " events");
  res.wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  return res;
}

}  // namespace eds
