#include "system/odometry.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <functional>
#include <limits>
#include <unordered_map>

#include "core/error.hpp"
#include "core/undistorter.hpp"
#include "frontend/event_packets.hpp"
#include "init/bootstrap.hpp"
#include "system/event_frontend.hpp"
#include "system/frame_frontend.hpp"
#include "system/odometry_config_io.hpp"
#include "system/run_stats.hpp"
#include "system/trajectory_smoothing.hpp"

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

namespace {

// The pipeline: frames through the bootstrap and the frame front-end, event frames (when used) through
// the event front-end, each given in time order.
class Core {
 public:
  Core(const CameraModel& camera, const OdometryConfig& cfg, OdometryResult& res, StageClock& clock)
      : cfg_(cfg),
        res_(res),
        clock_(clock),
        und_(camera),
        quality_(cfg.frame_quality),
        odo_(und_.pinhole(), cfg, res, &clock),
        boot_(und_.pinhole(), cfg.bootstrap),
        events_(und_.pinhole(), cfg.events) {}

  // A raw 8-bit frame.
  void frame(TimeNs t, const cv::Mat& raw) {
    ++res_.frames_in;
    std::optional<ScopedStage> stage(std::in_place, &clock_, Stage::kFramePreparation);
    if (std::string why = quality_.check(t, raw); !why.empty()) {
      ++res_.frames_rejected;
      ++inputs_without_pose_;
      res_.failures.push_back({t, "frame not used: " + why});
      return;
    }
    cv::Mat img;
    und_.undistortImage(raw).convertTo(img, CV_32F, 1.0 / 255.0);
    last_t_ = t;
    if (!res_.initialized) {
      stage.emplace(&clock_, Stage::kBootstrap);
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
    stage.emplace(&clock_, Stage::kFrameTracking);
    std::optional<SE3> found;
    if (cfg_.recovery.enabled && !recover(t, img, found)) return;
    const bool prior = has_event_pose_ && std::llabs(t - last_event_.t) < fromSeconds(0.05);
    const SE3 T_w_f = odo_.track(t, img, found ? &*found : prior ? &last_event_.T_w_c : nullptr);
    res_.frames.push_back({t, T_w_f});
    res_.frame_anchors.push_back({odo_.referenceId(), odo_.T_w_kf().inverse() * T_w_f});
    if (odo_.lastTrackOk()) {
      events_.correct(t, T_w_f);
      last_good_t_ = t;
      failed_in_row_ = 0;
      inputs_without_pose_ = 0;
    } else {
      ++inputs_without_pose_;
      if (++failed_in_row_ >= cfg_.recovery.failed_frames && cfg_.recovery.enabled)
        loseTrack(t, std::to_string(failed_in_row_) + " frame alignments failed in a row");
    }
    syncReference();
  }

  void eventFrame(const EventFrame& ef) {
    const ScopedStage stage(&clock_, Stage::kEventTracking);
    ++res_.event_frames;
    if (!res_.initialized) {
      // Kept until the map exists, then tracked (poses from the bootstrap's reference frame on: older
      // ones are dropped at once, which bounds the buffer by the bootstrap's span).
      pruneBuffered();
      buffered_.push_back({ef.t, ef.t_first, ef.t_last, ef.delta.clone()});
      if (boot_events_ && boot_events_->hasReference()) {
        if (const std::optional<SE3> T = boot_events_->track(ef, nullptr)) {
          boot_event_ = {ef.t, *T};
          has_boot_event_ = true;
        }
      }
      return;
    }
    if (lost_) {
      res_.failures.push_back({ef.t, "event frame: the track is lost; waiting for a frame to relocalize"});
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
    last_good_t_ = t;
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

  // The track is lost after a gap with no pose from frames or events; while it is, each usable frame
  // is relocalized. False: still lost (this frame gives no pose). `found`: the relocalized pose.
  bool recover(TimeNs t, const cv::Mat& img, std::optional<SE3>& found) {
    // A gap alone is no loss (frames may be seconds apart); inputs that gave no pose over it are.
    if (!lost_ && inputs_without_pose_ > 0 && t - last_good_t_ > fromSeconds(cfg_.recovery.gap_s))
      loseTrack(last_good_t_, "no pose from frames or events for " +
                                  std::to_string(std::lround(1000 * toSeconds(t - last_good_t_))) + " ms");
    if (!lost_) return true;
    TrackLoss& loss = res_.losses.back();
    ++loss.attempts;
    std::string how;
    found = odo_.relocalize(img, how);
    if (!found) {
      res_.failures.push_back({t, "track lost, relocalization: " + how});
      return false;
    }
    lost_ = false;
    failed_in_row_ = inputs_without_pose_ = 0;
    loss.t_recovered = t;
    loss.recovery = how;
    // The events start again from the frame's pose, at rest: their pose from before the loss is no prior.
    syncReference();
    events_.restartFrom(*found);
    has_event_pose_ = false;
    return true;
  }

  void loseTrack(TimeNs t_last_pose, const std::string& cause) {
    lost_ = true;
    res_.losses.push_back({t_last_pose, -1, cause, "", 0});
    res_.failures.push_back({t_last_pose, "track lost: " + cause});
  }

  void pruneBuffered() {
    const std::vector<BootstrapFrame>& bf = boot_.frames();
    const TimeNs t0 = boot_.hasReference() && !bf.empty() ? bf.front().t : std::numeric_limits<TimeNs>::max();
    std::erase_if(buffered_, [t0](const EventFrame& b) { return b.t < t0; });
  }

  // During the bootstrap the events track against its reference (its current inverse depths; 1 at
  // first): their pose at the next frame is the bootstrap's hint (frames far apart: a constant-velocity
  // guess is too far off). A new reference (a restart) is a new world: the tracking starts again.
  void syncBootstrapEvents(TimeNs t) {
    if (!cfg_.use_events || !boot_.hasReference()) return;
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
    const ScopedStage stage(&clock_, Stage::kEventTracking);
    const auto t0 = Clock::now();
    std::string why;
    const std::optional<SE3> T = bracket.first
                                     ? events_.trackBetween(ef, bracket.first->t, bracket.first->T_w_c,
                                                            bracket.second->t, bracket.second->T_w_c, &why)
                                     : events_.track(ef, prior, &why);
    res_.event_track_ms.push_back(msSince(t0));
    if (!T) {
      res_.failures.push_back({ef.t, "event frame: " + why});
      ++inputs_without_pose_;
      return;
    }
    if (plausible && !plausible(*T)) {
      res_.failures.push_back({ef.t, "event frame during the bootstrap: too far from the frames' poses"});
      return;
    }
    ++res_.events_tracked;
    last_good_t_ = ef.t;
    inputs_without_pose_ = 0;
    last_event_ = {ef.t, *T};
    has_event_pose_ = true;
    res_.events.push_back(last_event_);
    res_.event_last_t.push_back(ef.t_last);
    res_.event_anchors.push_back({events_.referenceId(), events_.T_w_kf().inverse() * *T});
    if (events_.referenceId() != snapshot_ref_id_) snapshot(ef);
  }

  // Every stride-th keyframe's first event frame; at kMax, every other one goes and the stride doubles.
  void snapshot(const EventFrame& ef) {
    snapshot_ref_id_ = events_.referenceId();
    if (snapshot_refs_++ % snapshot_stride_ != 0) return;
    auto& shots = res_.event_snapshots;
    shots.push_back(
        {ef.t, snapshot_ref_id_, events_.lastCorrelation(), ef.delta.clone(), events_.lastPrediction()});
    if (shots.size() < EventFrameSnapshot::kMax) return;
    for (std::size_t i = 1; 2 * i < shots.size(); ++i) shots[i] = std::move(shots[2 * i]);
    shots.resize((shots.size() + 1) / 2);
    snapshot_stride_ *= 2;
  }

  const OdometryConfig& cfg_;
  OdometryResult& res_;
  StageClock& clock_;
  Undistorter und_;
  FrameQualityGate quality_;
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
  TimeNs last_good_t_ = 0;  // of the last pose from a frame or event frame
  bool lost_ = false;
  int failed_in_row_ = 0;        // frame alignments
  int inputs_without_pose_ = 0;  // frames and event frames since the last pose
  int snapshot_ref_id_ = -1;
  std::size_t snapshot_refs_ = 0, snapshot_stride_ = 1;
};

}  // namespace

// The stream merge in front of the core (StreamConfig), and the listener's notifications.
class Odometry::Impl {
 public:
  Impl(const CameraModel& camera, const OdometryConfig& cfg, OdometryListener* listener)
      : wall0_(Clock::now()),
        cfg_(validated(cfg, camera)),
        listener_(listener),
        core_(camera, cfg_, res_, clock_),
        builder_(core_.undistorter(), cfg_.event_frame),
        n_(static_cast<std::size_t>(cfg_.event_frame.num_events)),
        starts_(cfg_.event_frame.stride(), cfg_.event_frame.max_rate_hz),
        lookahead_(cfg_.event_frame.lookahead()),
        flicker_(camera.width, camera.height, cfg_.flicker_filter) {}

  void addEvents(const EventArray& ev, std::size_t begin, std::size_t end) {
    const ScopedStage api(&clock_, Stage::kUnaccounted);
    checkOpen();
    if (!cfg_.use_events) return;
    end = std::min(end, ev.size());
    std::optional<ScopedStage> intake(std::in_place, &clock_, Stage::kEventIntake);
    const int w = core_.undistorter().raw().width, h = core_.undistorter().raw().height;
    TimeNs prev = checked_t_;  // committed only when the whole chunk is valid
    for (std::size_t i = begin; i < end; ++i) {
      if (ev.t[i] < prev)
        throw std::invalid_argument("Odometry::addEvents: event " + std::to_string(events_in_ + i - begin) +
                                    " at t = " + std::to_string(ev.t[i]) +
                                    " ns is before the one before it (" + std::to_string(prev) + " ns)");
      if (ev.x[i] >= w || ev.y[i] >= h || (ev.p[i] != 1 && ev.p[i] != -1))
        throw std::invalid_argument("Odometry::addEvents: event " + std::to_string(events_in_ + i - begin) +
                                    " at pixel (" + std::to_string(ev.x[i]) + ", " + std::to_string(ev.y[i]) +
                                    ") polarity " + std::to_string(ev.p[i]) + " is outside the " +
                                    std::to_string(w) + "x" + std::to_string(h) + " sensor or not +-1");
      prev = ev.t[i];
    }
    checked_t_ = prev;
    events_in_ += end - begin;
    intake.reset();
    for (std::size_t i = begin; i < end;) {
      // Appends no more than the next packet needs, so that every packet is built as soon as it can
      // be whatever the chunk size (the same event frames, in the same order).
      const std::size_t need =
          pos_ + n_ + lookahead_ > buf_.size() ? pos_ + n_ + lookahead_ - buf_.size() : 1;
      const std::size_t k = std::min(end - i, need);
      append(ev, i, i + k);
      i += k;
      buildPackets(false);
      dispatch(false);
    }
  }

  void addFrame(TimeNs t, const cv::Mat& gray8) {
    const ScopedStage api(&clock_, Stage::kUnaccounted);
    checkOpen();
    const cv::Size size(core_.undistorter().raw().width, core_.undistorter().raw().height);
    if (gray8.empty() || gray8.type() != CV_8UC1 || gray8.size() != size)
      throw std::invalid_argument("Odometry::addFrame: frame at t = " + std::to_string(t) +
                                  " ns is not an 8-bit gray image of the sensor's size " +
                                  std::to_string(size.width) + "x" + std::to_string(size.height));
    if (has_frame_in_ && t <= last_frame_in_)
      throw std::invalid_argument("Odometry::addFrame: frame at t = " + std::to_string(t) +
                                  " ns is not after the previous frame (" + std::to_string(last_frame_in_) +
                                  " ns)");
    has_frame_in_ = true;
    last_frame_in_ = t;
    {
      const ScopedStage prep(&clock_, Stage::kFramePreparation);
      frames_.push_back({t, gray8.clone()});
    }
    dispatch(false);
  }

  const OdometryResult& finish() {
    const ScopedStage api(&clock_, Stage::kUnaccounted);
    checkOpen();
    finished_ = true;
    buildPackets(true);
    dispatch(true);
    FrameFrontend& odo = core_.frontend();
    odo.worker().finish();
    const ScopedStage results(&clock_, Stage::kResults);
    const SlidingWindow& window = odo.worker().window();
    const BackendTimings& bt = odo.worker().timings();
    res_.mapping_ms = bt.mapping_ms;
    res_.ba_ms = bt.ba_ms;
    res_.window_points = bt.window_points;
    res_.keyframe_maps = window.retiredKeyframes();
    std::sort(res_.keyframe_maps.begin(), res_.keyframe_maps.end(),
              [](const auto& a, const auto& b) { return a.t < b.t; });
    for (const RetiredKeyframe& k : res_.keyframe_maps) res_.keyframes.push_back({k.t, k.T_w_kf});
    res_.pinhole = core_.undistorter().pinhole();
    res_.map = window.retiredPoints();
    res_.frames_refined = refinedTrajectory(res_.frames, res_.frame_anchors, window.retiredKeyframes());
    res_.events_refined =
        smoothPositions(refinedTrajectory(res_.events, res_.event_anchors, window.retiredKeyframes()),
                        cfg_.event_smoothing_s);
    TimeNs last_t = core_.lastTime();
    if (!res_.events.empty()) last_t = std::max(last_t, res_.events.back().t);
    res_.sequence_s = has_first_ ? toSeconds(last_t - res_.first_t) : 0.0;
    res_.peak_rss_mb = peakRssMb();
    res_.stages_s = clock_.seconds();
    if (cfg_.threaded_backend) res_.backend_stages_s = odo.worker().threadStageSeconds();
    res_.wall_s = std::chrono::duration<double>(Clock::now() - wall0_).count();
    return res_;
  }

  const OdometryResult& result() const { return res_; }

 private:
  struct PendingFrame {
    TimeNs t;
    cv::Mat image;
  };

  static const OdometryConfig& validated(const OdometryConfig& cfg, const CameraModel& camera) {
    validateOdometryConfig(cfg, camera);
    return cfg;
  }

  void checkOpen() const {
    if (finished_) throw std::logic_error("Odometry: used after finish()");
  }

  void append(const EventArray& ev, std::size_t a, std::size_t b) {
    const ScopedStage stage(&clock_, Stage::kEventIntake);
    if (pos_ > (1u << 20)) compact();
    for (std::size_t i = a; i < b; ++i)
      if (flicker_.keep(ev.t[i], ev.x[i], ev.y[i], ev.p[i]))
        buf_.push_back(ev.t[i], ev.x[i], ev.y[i], ev.p[i]);
    res_.events_flicker_dropped = flicker_.dropped();
    if (b > a) newest_t_ = ev.t[b - 1];
  }

  // Drops the events before the next packet: the builder's per-pixel memory has run past them.
  void compact() {
    eraseFront(buf_, pos_);
    base_ += pos_;
    pos_ = 0;
  }

  // Every packet whose events (and lookahead) have arrived; at the end, every complete packet.
  void buildPackets(bool at_end) {
    const ScopedStage stage(&clock_, Stage::kEventFrames);
    for (;;) {
      starts_.skip(buf_, pos_);
      if (buf_.size() < pos_ + n_ + (at_end ? 0 : lookahead_)) break;
      EventFrame ef;
      if (!spare_.empty()) {
        ef = std::move(spare_.back());
        spare_.pop_back();
      }
      builder_.build(buf_, pos_, ef, base_);
      efs_.push_back(std::move(ef));
      starts_.advance(buf_, pos_);
    }
  }

  // Processes waiting items in time order while the order is certain (or a wait ran out).
  void dispatch(bool at_end) {
    while (!frames_.empty() || !efs_.empty()) {
      if (!frames_.empty() && !efs_.empty()) {
        if (frames_.front().t <= efs_.front().t)
          processFrame();
        else
          processEventFrame();
      } else if (!frames_.empty()) {
        const bool events_past =
            !cfg_.use_events || (pos_ < buf_.size() && buf_.t[pos_] >= frames_.front().t);
        if (!(at_end || events_past ||
              frames_.size() > static_cast<std::size_t>(cfg_.stream.max_pending_frames)))
          return;
        processFrame();
      } else {
        const TimeNs t = efs_.front().t;
        const bool frame_past = has_frame_in_ && last_frame_in_ >= t;
        if (!(at_end || frame_past || newest_t_ - t > fromSeconds(cfg_.stream.max_frame_wait_s))) return;
        processEventFrame();
      }
    }
  }

  void processFrame() {
    const PendingFrame f = std::move(frames_.front());
    frames_.pop_front();
    if (!has_first_) has_first_ = true, res_.first_t = f.t;
    last_frame_done_ = f.t;
    core_.frame(f.t, f.image);
    notify();
  }

  void processEventFrame() {
    EventFrame ef = std::move(efs_.front());
    efs_.pop_front();
    // Before the first frame: nothing to track against yet (a recording's events before its frames).
    if (has_first_ && ef.t >= res_.first_t) {
      if (ef.t < last_frame_done_) {
        // A frame after it went ahead (the events stalled): too late to be tracked in order.
        res_.failures.push_back({ef.t, "event frame: arrived after a later frame was processed"});
      } else {
        core_.eventFrame(ef);
      }
      notify();
    }
    spare_.push_back(std::move(ef));
  }

  // Tells the listener what the last item produced.
  void notify() {
    if (!listener_) return;
    const ScopedStage stage(&clock_, Stage::kResults);
    if (res_.initialized && !told_init_) listener_->onInitialized(res_.init_t), told_init_ = true;
    FrameFrontend& odo = core_.frontend();
    if (res_.initialized && odo.referenceId() != told_kf_) {
      told_kf_ = odo.referenceId();
      listener_->onKeyframe({told_kf_, odo.reference().t, odo.T_w_kf(), odo.reference().points.size()});
    }
    for (; told_frames_ < res_.frames.size(); ++told_frames_)
      listener_->onFramePose(res_.frames[told_frames_], res_.frame_anchors[told_frames_].kf_id);
    for (; told_events_ < res_.events.size(); ++told_events_)
      listener_->onEventPose(res_.events[told_events_], res_.event_anchors[told_events_].kf_id);
    for (; told_failures_ < res_.failures.size(); ++told_failures_)
      listener_->onFailure(res_.failures[told_failures_]);
  }

  Clock::time_point wall0_;
  const OdometryConfig cfg_;
  OdometryListener* listener_;
  OdometryResult res_;
  StageClock clock_{Stage::kInput};  // the calling thread's
  Core core_;
  EventFrameBuilder builder_;
  std::size_t n_;
  PacketStarts starts_;
  std::size_t lookahead_;
  // Events not yet in a packet (from pos_ on) and the packets' lookahead; base_: stream index of buf_[0].
  EventArray buf_;
  FlickerFilter flicker_;  // in front of buf_: flickering pixels' events never enter it
  std::size_t pos_ = 0, events_in_ = 0;
  std::uint64_t base_ = 0;
  // The newest event validated (the chunk being added) and the newest appended to buf_ (the waits
  // measure from it, so that they do not depend on the chunk size).
  TimeNs checked_t_ = std::numeric_limits<TimeNs>::min(), newest_t_ = std::numeric_limits<TimeNs>::min();
  std::deque<PendingFrame> frames_;
  std::deque<EventFrame> efs_;
  std::vector<EventFrame> spare_;  // processed event frames, their images reused
  bool has_frame_in_ = false, has_first_ = false, finished_ = false;
  TimeNs last_frame_in_ = 0, last_frame_done_ = std::numeric_limits<TimeNs>::min();
  bool told_init_ = false;
  int told_kf_ = -1;
  std::size_t told_frames_ = 0, told_events_ = 0, told_failures_ = 0;
};

Odometry::Odometry(const CameraModel& camera, const OdometryConfig& cfg, OdometryListener* listener)
    : impl_(std::make_unique<Impl>(camera, cfg, listener)) {}
Odometry::~Odometry() = default;
void Odometry::addEvents(const EventArray& events, std::size_t begin, std::size_t end) {
  impl_->addEvents(events, begin, end);
}
void Odometry::addFrame(TimeNs t, const cv::Mat& gray8) { impl_->addFrame(t, gray8); }
const OdometryResult& Odometry::finish() { return impl_->finish(); }
const OdometryResult& Odometry::result() const { return impl_->result(); }

}  // namespace eds
