#include "system/odometry.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <unordered_map>

#include "core/error.hpp"
#include "core/undistorter.hpp"
#include "frontend/event_packets.hpp"
#include "init/bootstrap.hpp"
#include "io/ply.hpp"
#include "system/event_frontend.hpp"
#include "system/frame_frontend.hpp"
#include "system/run_stats.hpp"

namespace eds {

namespace {

double peakRssMb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;  // kB on Linux
}

// Each pose through its keyframe's final pose, and a keyframe's own frame at its final pose; a pose
// without a keyframe (or whose keyframe the window never retired) stays as tracked.
Trajectory refinedTrajectory(const Trajectory& traj, const std::vector<PoseAnchor>& anchors,
                             const std::vector<RetiredKeyframe>& keyframes) {
  std::unordered_map<int, const SE3*> by_id;
  std::unordered_map<TimeNs, const SE3*> by_time;
  for (const RetiredKeyframe& k : keyframes) by_id.emplace(k.id, &k.T_w_kf), by_time.emplace(k.t, &k.T_w_kf);
  Trajectory out = traj;
  for (std::size_t i = 0; i < out.size() && i < anchors.size(); ++i) {
    if (const auto own = by_time.find(out[i].t); own != by_time.end())
      out[i].T_w_c = *own->second;
    else if (const auto kf = by_id.find(anchors[i].kf_id); kf != by_id.end())
      out[i].T_w_c = *kf->second * anchors[i].T_kf_c;
  }
  return out;
}

}  // namespace

std::vector<std::size_t> selectFrames(const std::vector<FrameRef>& frames, double start_s, double duration_s,
                                      double frame_rate) {
  std::vector<std::size_t> out;
  if (frames.empty()) return out;
  const TimeNs t0 = frames.front().t + fromSeconds(start_s);
  const TimeNs t1 = duration_s > 0 ? t0 + fromSeconds(duration_s) : std::numeric_limits<TimeNs>::max();
  std::vector<std::size_t> in;
  for (std::size_t i = 0; i < frames.size(); ++i)
    if (frames[i].t >= t0 && frames[i].t <= t1) in.push_back(i);
  if (!(frame_rate > 0) || in.empty()) return in;
  const TimeNs step = fromSeconds(1.0 / frame_rate);
  std::size_t j = 0;
  for (TimeNs target = frames[in.front()].t; target <= frames[in.back()].t + step / 2; target += step) {
    while (j + 1 < in.size() &&
           std::llabs(frames[in[j + 1]].t - target) <= std::llabs(frames[in[j]].t - target))
      ++j;
    if (out.empty() || out.back() != in[j]) out.push_back(in[j]);
  }
  return out;
}

namespace {

// The run: frames through the bootstrap and the frame front-end, event frames (when used) through the
// event front-end, merged in time order.
class Runner {
 public:
  Runner(const Sequence& seq, const OdometryConfig& cfg, OdometryResult& res)
      : seq_(seq),
        cfg_(cfg),
        res_(res),
        und_(seq.camera()),
        odo_(und_.pinhole(), cfg, res),
        boot_(und_.pinhole(), cfg.bootstrap),
        events_(und_.pinhole(), cfg.events) {}

  void frame(std::size_t i) {
    const TimeNs t = seq_.frames()[i].t;
    cv::Mat img;
    und_.undistortImage(seq_.loadFrame(i)).convertTo(img, CV_32F, 1.0 / 255.0);
    ++res_.frames_in;
    last_t_ = t;
    if (!res_.initialized) {
      // The events' pose at this frame, tracked against the bootstrap's reference, seeds its alignment.
      SE3 hint;
      const bool has_hint = has_boot_event_ && std::llabs(t - boot_event_.t) < fromSeconds(0.05);
      if (has_hint) hint = boot_event_.T_w_c.inverse();
      if (boot_.add(t, img, has_hint ? &hint : nullptr))
        initialize(t, img);
      else
        syncBootstrapEvents(t);
      return;
    }
    // The event pose is the frame's prior when an event frame was tracked close to the frame's time.
    const bool prior = has_event_pose_ && std::llabs(t - last_event_.t) < fromSeconds(0.05);
    const SE3 T_w_f = odo_.track(t, img, prior ? &last_event_.T_w_c : nullptr);
    res_.frames.push_back({t, T_w_f});
    res_.frame_anchors.push_back({odo_.referenceId(), odo_.T_w_kf().inverse() * T_w_f});
    if (odo_.lastTrackOk()) events_.correct(t, T_w_f);
    syncReference();
  }

  void eventFrame(const EventFrame& ef) {
    ++res_.event_frames;
    if (!res_.initialized) {
      // Kept until the map exists, then tracked (poses from the first frame on).
      buffered_.push_back({ef.t, ef.t_first, ef.t_last, ef.delta.clone()});
      if (boot_events_ && boot_events_->hasReference()) {
        if (const std::optional<SE3> T = boot_events_->track(ef, nullptr)) {
          boot_event_ = {ef.t, *T};
          has_boot_event_ = true;
        }
      }
      return;
    }
    odo_.adoptReference(false);
    syncReference();
    trackEvents(ef, nullptr);
  }

  TimeNs lastTime() const { return last_t_; }
  FrameFrontend& frontend() { return odo_; }
  const Undistorter& undistorter() const { return und_; }

 private:
  void initialize(TimeNs t, const cv::Mat& img) {
    res_.initialized = true;
    res_.init_t = t;
    res_.init_frames = static_cast<int>(boot_.frames().size());
    res_.init_restarts = boot_.restarts();
    // Keyframe 0 is the reference with the bootstrap's depths; keyframe 1 the frame that completed it.
    const Keyframe& ref = boot_.reference();
    odo_.addKeyframe(ref.t, ref.image, SE3(), 0.0, 0.0, ref.points);
    const BootstrapFrame& last = boot_.frames().back();
    Trajectory boot_traj;
    for (const BootstrapFrame& f : boot_.frames()) boot_traj.push_back({f.t, f.T_ref_c});
    // The bootstrap's poses are relative to its reference, keyframe 0 (at the identity).
    for (std::size_t k = 0; k + 1 < boot_traj.size(); ++k) {
      res_.frames.push_back(boot_traj[k]);
      res_.frame_anchors.push_back({0, boot_traj[k].T_w_c});
    }
    odo_.setLast(boot_traj[boot_traj.size() - 2].T_w_c);
    odo_.setLastBrightness(last.a, last.b);
    const SE3 T_w_f = odo_.addKeyframe(t, img, last.T_ref_c, last.a, last.b);
    odo_.setLast(T_w_f);
    res_.frames.push_back({t, T_w_f});
    res_.frame_anchors.push_back({0, T_w_f});
    res_.tracked += boot_traj.size();
    if (!cfg_.use_events) return;
    // The event frames that arrived during the bootstrap, against the bootstrap's reference keyframe
    // (the first keyframe), each from the bootstrap's pose at its time.
    events_.setReference(ref, SE3());
    for (EventFrame& ef : buffered_) {
      if (ef.t < boot_traj.front().t) continue;
      const SE3 prior = poseAt(boot_traj, ef.t);
      // The frames bracket each of these event frames: a result far from their interpolation (more
      // than half the motion between the two frames, plus a margin) is a wrong minimum, not motion.
      const auto it = std::lower_bound(boot_traj.begin(), boot_traj.end(), ef.t,
                                       [](const StampedPose& p, TimeNs t) { return p.t < t; });
      const SE3& A = it == boot_traj.begin() ? it->T_w_c : (it - 1)->T_w_c;
      const SE3& B = it == boot_traj.end() ? (it - 1)->T_w_c : it->T_w_c;
      const SE3 AB = A.inverse() * B;
      const double max_t = 0.5 * AB.translation().norm() + cfg_.buffered_gate_translation;
      const double max_r = 0.5 * AB.so3().angle() + cfg_.buffered_gate_rotation_deg * M_PI / 180.0;
      const bool between = it != boot_traj.begin() && it != boot_traj.end();
      trackEvents(
          ef, &prior,
          [&](const SE3& T) {
            const SE3 d = prior.inverse() * T;
            return d.translation().norm() <= max_t && d.so3().angle() <= max_r;
          },
          between ? std::make_pair(&*(it - 1), &*it) : std::pair<const StampedPose*, const StampedPose*>{});
    }
    odo_.adoptReference(true);
    syncReference();
    buffered_.clear();
    // The bootstrap's last two frames start the motion prior (and the tracking) of the live events.
    const std::size_t n = res_.frames.size();
    if (n >= 2) events_.correct(res_.frames[n - 2].t, res_.frames[n - 2].T_w_c);
    if (n >= 1) events_.correct(res_.frames[n - 1].t, res_.frames[n - 1].T_w_c);
  }

  // During the bootstrap the events track against its reference (its current inverse depths; 1 at
  // first): their pose at the next frame is the bootstrap's hint. A new reference (a restart) is a new
  // world: the tracking starts again.
  void syncBootstrapEvents(TimeNs t) {
    if (!cfg_.use_events || !cfg_.bootstrap_from_events || !boot_.hasReference()) return;
    const Keyframe& ref = boot_.reference();
    if (!boot_events_ || ref.t != boot_ref_t_ || boot_.restarts() != boot_restarts_) {
      boot_events_.emplace(und_.pinhole(), cfg_.events);
      boot_ref_t_ = ref.t, boot_restarts_ = boot_.restarts();
      has_boot_event_ = false;
    }
    boot_events_->setReference(ref, SE3());
    const BootstrapFrame& last = boot_.frames().back();
    if (last.t == t) boot_events_->correct(t, last.T_ref_c);
  }

  void syncReference() {
    if (!cfg_.use_events || odo_.referenceId() == event_ref_id_ || odo_.reference().points.empty()) return;
    events_.setReference(odo_.reference(), odo_.T_w_kf());
    event_ref_id_ = odo_.referenceId();
  }

  // `bracket`: the frames before and after a buffered event frame (its start and motion prior).
  void trackEvents(const EventFrame& ef, const SE3* prior,
                   const std::function<bool(const SE3&)>& plausible = nullptr,
                   const std::pair<const StampedPose*, const StampedPose*>& bracket = {}) {
    const auto t0 = Clock::now();
    std::string why;
    const std::optional<SE3> T = bracket.first
                                     ? events_.trackBetween(ef, bracket.first->t, bracket.first->T_w_c,
                                                            bracket.second->t, bracket.second->T_w_c, &why)
                                     : events_.track(ef, prior, &why);
    res_.event_track_ms.push_back(msSince(t0));
    if (!T) {
      res_.failures.push_back({ef.t, "event frame: " + why});
      return;
    }
    if (plausible && !plausible(*T)) {
      res_.failures.push_back({ef.t, "event frame during the bootstrap: too far from the frames' poses"});
      return;
    }
    ++res_.events_tracked;
    last_event_ = {ef.t, *T};
    has_event_pose_ = true;
    res_.events.push_back(last_event_);
    res_.event_anchors.push_back({events_.referenceId(), events_.T_w_kf().inverse() * *T});
  }

  const Sequence& seq_;
  const OdometryConfig& cfg_;
  OdometryResult& res_;
  Undistorter und_;
  FrameFrontend odo_;
  Bootstrap boot_;
  EventFrontend events_;
  int event_ref_id_ = -1;
  std::vector<EventFrame> buffered_;
  std::optional<EventFrontend> boot_events_;  // events against the bootstrap's reference
  TimeNs boot_ref_t_ = -1;
  int boot_restarts_ = -1;
  StampedPose boot_event_;
  bool has_boot_event_ = false;
  StampedPose last_event_;
  bool has_event_pose_ = false;
  TimeNs last_t_ = 0;
};

}  // namespace

OdometryResult runOdometry(const Sequence& seq, const OdometryConfig& cfg, const ProgressFn& progress) {
  const auto wall0 = Clock::now();
  if (!seq.hasFrames())
    throw InputError((seq.dir() / "images.txt").string(),
                     "the odometry needs frames (keyframes come from them)");
  if (cfg.use_events && !seq.hasEvents())
    throw InputError((seq.dir() / "events.txt").string(),
                     "no events in the sequence: run with --frames-only, or add events");
  if (cfg.frame_rate < 0 || cfg.start_s < 0 || cfg.duration_s < 0)
    throw std::invalid_argument("run: frame rate, start and duration must not be negative");
  cfg.event_frame.validate();
  OdometryResult res;
  Runner run(seq, cfg, res);
  const std::vector<std::size_t> idx =
      selectFrames(seq.frames(), cfg.start_s, cfg.duration_s, cfg.frame_rate);
  if (idx.empty())
    throw InputError((seq.dir() / "images.txt").string(), "no frame in the requested time range");
  res.first_t = seq.frames()[idx.front()].t;
  const TimeNs t_end =
      cfg.duration_s > 0 ? res.first_t + fromSeconds(cfg.duration_s) : std::numeric_limits<TimeNs>::max();
  std::size_t next = 0;  // next frame (index into idx)
  const TimeNs t_last_frame = std::min(seq.frames()[idx.back()].t, t_end);
  const double total_s = toSeconds(t_last_frame - res.first_t);
  TimeNs t_reported = res.first_t;
  auto report = [&](TimeNs t) {
    if (!progress || t - t_reported < fromSeconds(0.1)) return;
    t_reported = t;
    progress(std::min(toSeconds(t - res.first_t), total_s), total_s);
  };
  if (cfg.use_events) {
    auto src = seq.openEvents();
    EventPacketStream packets(*src, static_cast<std::size_t>(cfg.event_frame.num_events),
                              cfg.event_frame.stride(), cfg.event_frame.lookahead());
    EventFrameBuilder builder(run.undistorter(), cfg.event_frame);
    const EventArray* events = nullptr;
    std::size_t begin = 0;
    EventFrame ef;
    while (packets.next(events, begin)) {
      builder.build(*events, begin, ef, packets.base());
      if (ef.t < res.first_t) continue;
      if (ef.t > t_end) break;
      while (next < idx.size() && seq.frames()[idx[next]].t <= ef.t) run.frame(idx[next++]);
      run.eventFrame(ef);
      report(ef.t);
    }
  }
  while (next < idx.size()) {
    run.frame(idx[next]);
    report(seq.frames()[idx[next++]].t);
  }
  if (progress) progress(total_s, total_s);
  TimeNs last_t = run.lastTime();
  if (!res.events.empty()) last_t = std::max(last_t, res.events.back().t);

  FrameFrontend& odo = run.frontend();
  odo.worker().waitIdle();
  SlidingWindow& window = odo.worker().window();
  // The last keyframes had fewer solves than the ones before them: converge the window once more before
  // writing it (ECD slider rotation drift, median over 5 start times: 2.05 -> 1.64 deg).
  window.optimize();
  window.flush();
  const BackendTimings& bt = odo.worker().timings();
  res.mapping_ms = bt.mapping_ms;
  res.ba_ms = bt.ba_ms;
  res.window_points = bt.window_points;
  for (const RetiredKeyframe& k : window.retiredKeyframes()) res.keyframes.push_back({k.t, k.T_w_kf});
  std::sort(res.keyframes.begin(), res.keyframes.end(),
            [](const auto& a, const auto& b) { return a.t < b.t; });
  res.map = window.retiredPoints();
  res.frames_refined = refinedTrajectory(res.frames, res.frame_anchors, window.retiredKeyframes());
  res.events_refined = refinedTrajectory(res.events, res.event_anchors, window.retiredKeyframes());
  res.sequence_s = toSeconds(last_t - res.first_t);
  res.wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  res.peak_rss_mb = peakRssMb();
  return res;
}

void writeOdometryOutputs(const std::filesystem::path& dir, const OdometryResult& r,
                          const OdometryConfig& cfg) {
  std::filesystem::create_directories(dir);
  // The main files hold each pose through its keyframe's final pose (as DSO's results); *_live.txt the
  // poses as they were tracked, what a live user had at the time.
  writeTum(dir / "trajectory_frames.txt", r.frames_refined);
  writeTum(dir / "trajectory_frames_live.txt", r.frames);
  if (cfg.use_events) {
    writeTum(dir / "trajectory_events.txt", r.events_refined);
    writeTum(dir / "trajectory_events_live.txt", r.events);
  }
  writeTum(dir / "keyframes.txt", r.keyframes);
  PointCloud pc;
  for (const MapPoint& p : r.map) {
    pc.xyz.push_back(p.p_w.cast<float>());
    pc.intensity.push_back(p.intensity);
  }
  writePly(dir / "map.ply", pc);
  nlohmann::json j;
  j["mode"] = cfg.use_events ? "run (events + frames)" : "run --frames-only";
  j["initialized"] = r.initialized;
  j["initialization"] = {{"t", r.initialized ? toSeconds(r.init_t) : 0.0},
                         {"seconds_after_first_frame", r.initialized ? toSeconds(r.init_t - r.first_t) : 0.0},
                         {"frames_used", r.init_frames},
                         {"restarts", r.init_restarts}};
  j["counts"] = {{"frames", r.frames_in},          {"poses", r.frames.size()},
                 {"tracked", r.tracked},           {"failures", r.failures.size()},
                 {"event_frames", r.event_frames}, {"event_frames_tracked", r.events_tracked},
                 {"event_poses", r.events.size()}, {"keyframes", r.keyframes.size()},
                 {"map_points", r.map.size()},     {"backend_waits", r.backend_waits}};
  j["timings_ms"] = {{"frame_tracking", timingStats(r.track_ms)},
                     {"event_tracking", timingStats(r.event_track_ms)},
                     {"mapping", timingStats(r.mapping_ms)},
                     {"backend_per_keyframe", timingStats(r.ba_ms)}};
  std::vector<double> wp(r.window_points.begin(), r.window_points.end());
  j["window_points"] = timingStats(wp);
  j["wall_s"] = r.wall_s;
  j["sequence_s"] = r.sequence_s;
  j["real_time_factor"] = r.sequence_s > 0 ? r.wall_s / r.sequence_s : 0.0;
  j["peak_rss_mb"] = r.peak_rss_mb;
  nlohmann::json fails = nlohmann::json::array();
  for (const auto& f : r.failures) fails.push_back({{"t", toSeconds(f.t)}, {"reason", f.reason}});
  j["failures"] = fails;
  j["config"] = {{"frame_rate", cfg.frame_rate},
                 {"start_s", cfg.start_s},
                 {"duration_s", cfg.duration_s},
                 {"window", cfg.backend.window},
                 {"points_per_keyframe", cfg.backend.points_per_keyframe},
                 {"marginalize", cfg.backend.marginalize},
                 {"threaded_backend", cfg.threaded_backend}};
  std::ofstream out(dir / "summary.json");
  if (!out) throw InputError((dir / "summary.json").string(), "cannot open for writing");
  out << j.dump(2) << "\n";
}

}  // namespace eds
