#include "system/odometry_core.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <unordered_map>

#include "frontend/exposure_deblur.hpp"
#include "system/backward_events.hpp"
#include "system/buffered_gate.hpp"
#include "system/run_stats.hpp"
#include "system/trajectory_smoothing.hpp"

namespace eds {

namespace {

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

// Keeps `ef` in half precision (its values have unit norm: 11 bits suffice) unless it comes closer
// than min_dt after the last one kept. Beyond max_mb the frames are thinned to twice their mean spacing
// (evenly, so that they still span their time), which becomes min_dt for those to come. True when it
// thinned.
bool keepHalfPrecision(std::vector<EventFrame>& kept, TimeNs& min_dt, const EventFrame& ef, double max_mb) {
  if (!kept.empty() && ef.t - kept.back().t < min_dt) return false;
  kept.push_back({ef.t, ef.t_first, ef.t_last, cv::Mat()});
  ef.delta.convertTo(kept.back().delta, CV_16F);
  const double bytes = static_cast<double>(kept.size()) * static_cast<double>(kept.back().delta.total()) *
                       static_cast<double>(kept.back().delta.elemSize());
  if (bytes <= max_mb * 1024 * 1024 || kept.size() < 2) return false;
  min_dt = 2 * (kept.back().t - kept.front().t) / static_cast<TimeNs>(kept.size() - 1);
  std::size_t n = 1;
  for (std::size_t i = 1; i < kept.size(); ++i)
    if (kept[i].t - kept[n - 1].t >= min_dt) kept[n++] = std::move(kept[i]);
  kept.resize(n);
  return true;
}

}  // namespace

std::vector<TimeNs> segmentStartTimes(const OdometryResult& r) {
  std::vector<TimeNs> out;
  for (std::size_t k = 1; k < r.segments.size(); ++k) out.push_back(r.segments[k].t_start);
  return out;
}

OdometryCore::OdometryCore(const CameraModel& camera, const OdometryConfig& cfg, OdometryResult& res,
                           StageClock& clock)
    : cfg_(cfg),
      res_(res),
      clock_(clock),
      und_(camera),
      quality_(cfg.frame_quality),
      odo_(std::make_unique<FrameFrontend>(und_.pinhole(), cfg, res, &clock)),
      boot_(std::make_unique<Bootstrap>(und_.pinhole(), cfg.bootstrap)),
      events_(std::make_unique<EventFrontend>(und_.pinhole(), cfg.events)) {}

void OdometryCore::frame(TimeNs t, const cv::Mat& raw) {
  ++res_.frames_in;
  {
    const ScopedStage results(&clock_, Stage::kResults);  // the listener may write them out
    collectRetired();
  }
  const ScopedStage stage(&clock_, Stage::kFramePreparation);
  if (std::string why = quality_.check(t, raw); !why.empty()) {
    ++res_.frames_rejected;
    if (initialized_ && !lost_) {
      // The keyframe being mapped is waited for, adjusted, so that the events, which carry the pose
      // alone until the next usable frame, track against it optimized and not against its frame.
      odo_->awaitPendingKeyframe(true);
      syncReference();
    }
    if (trackRefused(t, raw)) {
      res_.failures.push_back({t, "frame kept out of the map: " + why + "; its pose tracked"});
      return;
    }
    ++inputs_without_pose_;
    res_.failures.push_back({t, "frame not used: " + why});
    return;
  }
  cv::Mat img;
  und_.undistortImage(raw).convertTo(img, CV_32F, 1.0 / 255.0);
  last_t_ = t;
  if (res_.segments.empty()) res_.segments.push_back({0, t, -1, ""});
  if (!initialized_)
    bootstrapFrame(t, img);
  else
    trackFrame(t, img);
}

// Bright or dark as it may be, a refused frame still holds the scene where it is not clipped: the pose
// it gives anchors the events' (which otherwise drift until the next usable frame), or bridges the gap
// a frames-only run would lose its track over. It never becomes a keyframe.
bool OdometryCore::trackRefused(TimeNs t, const cv::Mat& raw) {
  // Past the gap that makes a loss, the last pose is no start (the next usable frame relocalizes).
  if (!cfg_.frame_quality.track_refused || !initialized_ || lost_ ||
      t - last_good_t_ > fromSeconds(cfg_.recovery.gap_s))
    return false;
  const cv::Mat norm = normalizeRefusedFrame(raw, quality_.referenceMean());
  if (norm.empty()) return false;
  const cv::Mat img = und_.undistortImage(norm, std::numeric_limits<double>::quiet_NaN());
  const ScopedStage stage(&clock_, Stage::kFrameTracking);
  const bool event_prior = has_event_pose_ && std::llabs(t - last_event_.t) < fromSeconds(0.05);
  const std::optional<SE3> T_w_f = odo_->trackRefused(t, img, event_prior ? &last_event_.T_w_c : nullptr);
  if (!T_w_f) return false;
  res_.frames.push_back({t, *T_w_f});
  res_.frame_anchors.push_back({odo_->referenceId(), odo_->T_w_kf().inverse() * *T_w_f});
  frame_ok_.push_back(1);
  if (cfg_.use_events) events_->correct(t, *T_w_f, false);
  ++res_.frames_tracked_only;
  last_good_t_ = t;
  failed_in_row_ = inputs_without_pose_ = 0;
  return true;
}

void OdometryCore::bootstrapFrame(TimeNs t, const cv::Mat& img) {
  const ScopedStage stage(&clock_, Stage::kBootstrap);
  // The events' pose at this frame, tracked against the bootstrap's reference, seeds its alignment.
  SE3 hint;
  const bool has_hint = has_boot_event_ && std::llabs(t - boot_event_.t) < fromSeconds(0.05);
  if (has_hint) hint = boot_event_.T_w_c.inverse();
  if (boot_->add(t, img, has_hint ? &hint : nullptr))
    initialize(t, img);
  else
    syncBootstrapEvents(t);
}

void OdometryCore::trackFrame(TimeNs t, const cv::Mat& img) {
  const ScopedStage stage(&clock_, Stage::kFrameTracking);
  std::optional<SE3> found;
  if (cfg_.recovery.enabled && !recover(t, img, found)) {
    if (!initialized_) bootstrapFrame(t, img);  // a new segment starts with this frame
    return;
  }
  // The event pose is the frame's prior when an event frame was tracked close to the frame's time.
  const bool prior = has_event_pose_ && std::llabs(t - last_event_.t) < fromSeconds(0.05);
  const SE3 T_w_f = odo_->track(t, img, found ? &*found : prior ? &last_event_.T_w_c : nullptr);
  if (found && cfg_.use_events) trackEventsSinceLoss(t, odo_->lastTrackOk() ? T_w_f : *found);
  if (odo_->lastTrackOk()) {
    const bool sparse = cfg_.feature_start.sparse(last_aligned_.t, t);
    if (!found && sparse && cfg_.feature_start.retrack_events && !since_frame_.empty())
      res_.events_retracked += retrackEvents(since_frame_, last_aligned_, {t, T_w_f}, odo_->reference(),
                                             odo_->T_w_kf(), und_.pinhole(), cfg_, res_);
    sinceFrame({t, T_w_f}, sparse);
  }
  res_.frames.push_back({t, T_w_f});
  res_.frame_anchors.push_back({odo_->referenceId(), odo_->T_w_kf().inverse() * T_w_f});
  frame_ok_.push_back(odo_->lastTrackOk());
  if (odo_->lastTrackOk()) {
    events_->correct(t, T_w_f);
    // A keyframe the threaded back-end is still mapping: the events track against its frame at once,
    // not against the reference it replaces for the time the mapping takes.
    const FrameFrontend::Pending* kf = odo_->pendingKeyframe();
    if (cfg_.use_events && kf && kf->t == t)
      events_->setProvisionalReference(kf->id, t, img, kf->T_w_kf, kf->points);
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

void OdometryCore::eventFrame(const EventFrame& ef) {
  const ScopedStage stage(&clock_, Stage::kEventTracking);
  ++res_.event_frames;
  if (!initialized_) {
    // Kept until the map exists, then tracked (from buffered_before_reference_s before the bootstrap's
    // reference frame on: older ones are dropped at once, which bounds the buffer by the bootstrap's
    // span plus that). In half precision:
    // a second of them at 640x480 is 60 MB so (the values have unit norm; 11 bits suffice).
    pruneBuffered(ef.t);
    res_.buffered_thinned += keepHalfPrecision(buffered_, buffered_min_dt_, ef, cfg_.buffered_max_mb);
    if (boot_events_ && boot_events_->hasReference()) {
      if (const std::optional<SE3> T = boot_events_->track(ef, nullptr)) {
        boot_event_ = {ef.t, *T};
        has_boot_event_ = true;
      }
    }
    return;
  }
  if (lost_) {
    keepForBackfill(ef);
    res_.failures.push_back({ef.t, "event frame: the track is lost; waiting for a frame to relocalize"});
    return;
  }
  odo_->adoptReference(false);
  syncReference();
  const std::size_t n_before = res_.events.size();
  trackEvents(ef, nullptr);
  if (res_.events.size() == n_before) {
    keepForBackfill(ef);
    return;
  }
  buffered_.clear();
  keepSinceFrame(ef);
}

// An event frame that gave no pose since the last one: kept (those of the last recovery.backfill_s)
// to be tracked backwards if the track is lost and a frame relocalizes.
void OdometryCore::keepForBackfill(const EventFrame& ef) {
  const TimeNs t0 = std::max(ef.t - fromSeconds(cfg_.recovery.backfill_s), last_good_t_);
  std::erase_if(buffered_, [t0](const EventFrame& b) { return b.t <= t0; });
  if (buffered_.empty()) buffered_min_dt_ = 0;
  if (cfg_.recovery.backfill_s > 0)
    res_.buffered_thinned += keepHalfPrecision(buffered_, buffered_min_dt_, ef, cfg_.buffered_max_mb);
}

void OdometryCore::initialize(TimeNs t, const cv::Mat& img) {
  initialized_ = true;
  last_good_t_ = t;
  MapSegment& segment = res_.segments.back();
  segment.t_init = t;
  if (!res_.initialized) {
    res_.initialized = true;
    res_.init_t = t;
    res_.init_frames = static_cast<int>(boot_->frames().size());
    res_.init_restarts = boot_->restarts();
  } else if (!res_.losses.empty() && res_.losses.back().t_recovered < 0) {
    TrackLoss& loss = res_.losses.back();
    loss.t_recovered = t;
    loss.recovery = "new map (segment " + std::to_string(segment.id) + ")";
  }
  // The reference keyframe holds the bootstrap's depths; the next one is the frame that completed it.
  const Keyframe& ref = boot_->reference();
  const int ref_id = odo_->worker().nextId();
  odo_->addKeyframe(ref.t, ref.image, SE3(), 0.0, 0.0, ref.points);
  const BootstrapFrame& last = boot_->frames().back();
  Trajectory boot_traj;
  for (const BootstrapFrame& f : boot_->frames()) boot_traj.push_back({f.t, f.T_ref_c});
  // The bootstrap's poses are relative to its reference keyframe (at the identity).
  for (std::size_t k = 0; k + 1 < boot_traj.size(); ++k) {
    res_.frames.push_back(boot_traj[k]);
    res_.frame_anchors.push_back({ref_id, boot_traj[k].T_w_c});
    frame_ok_.push_back(1);
  }
  odo_->setLast(boot_traj[boot_traj.size() - 2].t, boot_traj[boot_traj.size() - 2].T_w_c);
  odo_->setLastBrightness(last.a, last.b);
  const SE3 T_w_f = odo_->addKeyframe(t, img, last.T_ref_c, last.a, last.b);
  odo_->setLast(t, T_w_f);
  res_.frames.push_back({t, T_w_f});
  res_.frame_anchors.push_back({ref_id, T_w_f});
  frame_ok_.push_back(1);
  res_.tracked += boot_traj.size();
  sinceFrame({t, T_w_f}, cfg_.feature_start.sparse(boot_traj[boot_traj.size() - 2].t, t));
  if (!cfg_.use_events) return;
  trackEventsBeforeReference(ref, boot_traj);
  events_->setReference(ref, SE3());
  trackBufferedEvents(boot_traj);
  buffered_.clear();
  buffered_min_dt_ = 0;
  // The bootstrap's last two frames start the motion prior (and the tracking) of the live events.
  // Before the new keyframe is adopted: a threaded back-end returns it optimized, in a world moved
  // from the frames' poses, and adopting it moves those poses along (they would pull the events away).
  const std::size_t n = res_.frames.size();
  if (n >= 2) events_->correct(res_.frames[n - 2].t, res_.frames[n - 2].T_w_c);
  if (n >= 1) events_->correct(res_.frames[n - 1].t, res_.frames[n - 1].T_w_c);
  odo_->adoptReference(true);
  syncReference();
}

// The event frames that arrived during the bootstrap, against its reference keyframe, each from the
// bootstrap's pose at its time.
void OdometryCore::trackBufferedEvents(const Trajectory& boot_traj) {
  StampedPose last{boot_traj.front().t, boot_traj.front().T_w_c};  // the last accepted pose
  EventFrame ef;
  for (const EventFrame& half : buffered_) {
    if (half.t < boot_traj.front().t) continue;
    ef.t = half.t, ef.t_first = half.t_first, ef.t_last = half.t_last;
    half.delta.convertTo(ef.delta, CV_32F);
    const BufferedEventGate gate(boot_traj, ef.t, last, cfg_.buffered_gate_translation,
                                 cfg_.buffered_gate_rotation_deg * M_PI / 180.0);
    last = gate.last();
    const SE3 prior = gate.interpolated();
    const std::size_t n_before = res_.events.size();
    trackEvents(ef, &prior, [&](const SE3& T) { return gate.accepts(T); }, {gate.before(), gate.after()});
    if (res_.events.size() > n_before) last = res_.events.back();
  }
}

// The event frames buffered before the bootstrap's reference, tracked backwards from it. Their
// speed bound is the bootstrap frames' mean speed; their poses go before all others.
void OdometryCore::trackEventsBeforeReference(const Keyframe& ref, const Trajectory& boot_traj) {
  const TimeNs t_ref = boot_traj.front().t;
  if (boot_traj.size() < 2 || buffered_.empty() || buffered_.front().t >= t_ref) return;
  const ScopedStage stage(&clock_, Stage::kEventTracking);
  const auto [speed_t, speed_r] = meanSpeed(boot_traj.front(), boot_traj.back());
  const BackwardPass pass{&ref,
                          SE3(),
                          boot_traj.front(),
                          std::numeric_limits<TimeNs>::min(),
                          speed_t,
                          speed_r,
                          "event frame before the bootstrap's reference"};
  trackEventsBackwards(buffered_, pass, und_.pinhole(), cfg_, res_);
}

void OdometryCore::sinceFrame(const StampedPose& frame, bool sparse) {
  since_frame_.clear();
  since_min_dt_ = 0;
  last_aligned_ = frame;
  sparse_frames_ = sparse;
}

void OdometryCore::keepSinceFrame(const EventFrame& ef) {
  // While frames come sparsely, from the last one on; else only once it is half a sparse interval
  // old (frames may have turned sparse): at video rate nothing is kept.
  if (!(cfg_.feature_start.min_interval_s > 0) || last_aligned_.t < 0 ||
      (!sparse_frames_ && ef.t - last_aligned_.t < fromSeconds(cfg_.feature_start.min_interval_s) / 2))
    return;
  keepHalfPrecision(since_frame_, since_min_dt_, ef, cfg_.buffered_max_mb);
}

// After a relocalization, the event frames kept while the track was lost, tracked backwards from the
// frame that recovered it (at T_w_f) against the current reference, down to the last pose before the
// loss. Their speed bound is the mean speed from that pose to the frame.
void OdometryCore::trackEventsSinceLoss(TimeNs t, const SE3& T_w_f) {
  TrackLoss& loss = res_.losses.back();
  std::optional<StampedPose> before;  // the last pose, from an event frame or a frame, before the loss
  if (!res_.events.empty() && res_.events.back().t <= loss.t_lost) before = res_.events.back();
  for (std::size_t k = res_.frames.size(); k-- > 0;) {
    if (res_.frames[k].t > loss.t_lost || !frame_ok_[k]) continue;
    if (!before || res_.frames[k].t > before->t) before = res_.frames[k];
    break;
  }
  if (before && !buffered_.empty() && t > before->t) {
    const ScopedStage stage(&clock_, Stage::kEventTracking);
    // The speed bound: the mean speed over the time lost, or over the second before the loss where
    // that was faster (a camera swinging back and forth moves little in the mean over seconds).
    auto it = std::lower_bound(res_.events.begin(), res_.events.end(), before->t - fromSeconds(1.0),
                               [](const StampedPose& p, TimeNs tt) { return p.t < tt; });
    const StampedPose earlier = it != res_.events.end() && it->t < before->t ? *it : *before;
    const auto [speed_t, speed_r] = meanSpeed(*before, {t, T_w_f});
    const auto [speed_t0, speed_r0] = meanSpeed(earlier, *before);
    const BackwardPass pass{&odo_->reference(),
                            odo_->T_w_kf(),
                            {t, T_w_f},
                            before->t + 1,
                            std::max(speed_t, speed_t0),
                            std::max(speed_r, speed_r0),
                            "event frame while the track was lost"};
    loss.event_poses_backfilled = trackEventsBackwards(buffered_, pass, und_.pinhole(), cfg_, res_);
  }
  buffered_.clear();
  buffered_min_dt_ = 0;
}

// The track is lost after a gap with no pose from frames or events; while it is, each usable frame
// is relocalized. False: still lost (this frame gives no pose). `found`: the relocalized pose.
bool OdometryCore::recover(TimeNs t, const cv::Mat& img, std::optional<SE3>& found) {
  // A gap alone is no loss (frames may be seconds apart); inputs that gave no pose over it are.
  if (!lost_ && inputs_without_pose_ > 0 && t - last_good_t_ > fromSeconds(cfg_.recovery.gap_s))
    loseTrack(last_good_t_, "no pose from frames or events for " +
                                std::to_string(std::lround(1000 * toSeconds(t - last_good_t_))) + " ms");
  if (!lost_) return true;
  TrackLoss& loss = res_.losses.back();
  ++loss.attempts;
  std::string how;
  found = odo_->relocalize(t, img, how);
  if (!found) {
    res_.failures.push_back({t, "track lost, relocalization: " + how});
    // The map is no help any more: a new one starts from this frame.
    if (loss.attempts >= cfg_.recovery.new_map_after_frames &&
        t - loss.t_lost >= fromSeconds(cfg_.recovery.new_map_after_s))
      startSegment(t);
    return false;
  }
  lost_ = false;
  failed_in_row_ = inputs_without_pose_ = 0;
  loss.t_recovered = t;
  loss.recovery = how;
  // The events start again from the frame's pose, at rest: their pose from before the loss is no prior.
  syncReference();
  events_->restartFrom(*found);
  has_event_pose_ = false;
  return true;
}

void OdometryCore::loseTrack(TimeNs t_last_pose, const std::string& cause) {
  lost_ = true;
  res_.losses.push_back({t_last_pose, -1, cause, "", 0});
  res_.failures.push_back({t_last_pose, "track lost: " + cause});
}

// A new map segment from `t` on: the old segment's back-end finishes (its keyframes and points are
// final), and the bootstrap, the trackers and the back-end start anew, keyframe ids going on.
void OdometryCore::startSegment(TimeNs t) {
  const ScopedStage stage(&clock_, Stage::kBootstrap);
  retireSegment();
  const int next_id = odo_->worker().nextId();
  odo_ = std::make_unique<FrameFrontend>(und_.pinhole(), cfg_, res_, &clock_, next_id);
  boot_ = std::make_unique<Bootstrap>(und_.pinhole(), cfg_.bootstrap);
  events_ = std::make_unique<EventFrontend>(und_.pinhole(), cfg_.events);
  boot_events_.reset();
  buffered_.clear();
  buffered_min_dt_ = 0;
  sinceFrame({-1, SE3()}, false);
  initialized_ = lost_ = has_boot_event_ = has_event_pose_ = false;
  boot_ref_t_ = -1, boot_restarts_ = -1, event_ref_version_ = -1;
  failed_in_row_ = inputs_without_pose_ = 0;
  res_.segments.push_back({static_cast<int>(res_.segments.size()), t, -1, res_.losses.back().cause});
  res_.failures.push_back({t, "track lost: relocalization keeps failing; a new map (segment " +
                                  std::to_string(res_.segments.back().id) + ") starts"});
}

void OdometryCore::retireSegment() {
  BackendWorker& worker = odo_->worker();
  worker.finish();
  collectRetired();
  std::vector<MapPoint> points = worker.window().takeRetiredPoints();
  retired_points_.insert(retired_points_.end(), points.begin(), points.end());
  const BackendTimings& bt = worker.timings();
  auto append = [](auto& to, const auto& from) { to.insert(to.end(), from.begin(), from.end()); };
  append(retired_timings_.mapping_ms, bt.mapping_ms);
  append(retired_timings_.ba_ms, bt.ba_ms);
  append(retired_timings_.window_points, bt.window_points);
  if (cfg_.threaded_backend) {
    const StageSeconds s = worker.threadStageSeconds();
    for (std::size_t i = 0; i < s.size(); ++i) retired_backend_stages_[i] += s[i];
  }
}

// A long run's keyframe images and points are most of its memory: a sink that stores them elsewhere
// keeps the result from growing with them.
void OdometryCore::collectRetired() {
  for (RetiredKeyframe& k : odo_->worker().takeRetired()) {
    if (retired_sink_ && retired_sink_(k)) {
      k.image.release();
      std::vector<KeyframePoint>().swap(k.points);
    }
    retired_keyframes_.push_back(std::move(k));
  }
}

void OdometryCore::finish() {
  retireSegment();
  const ScopedStage stage(&clock_, Stage::kResults);
  res_.mapping_ms = retired_timings_.mapping_ms;
  res_.ba_ms = retired_timings_.ba_ms;
  res_.window_points = retired_timings_.window_points;
  res_.backend_stages_s = retired_backend_stages_;
  res_.keyframe_maps = std::move(retired_keyframes_);
  std::sort(res_.keyframe_maps.begin(), res_.keyframe_maps.end(),
            [](const auto& a, const auto& b) { return a.t < b.t; });
  for (const RetiredKeyframe& k : res_.keyframe_maps) res_.keyframes.push_back({k.t, k.T_w_kf});
  res_.pinhole = und_.pinhole();
  res_.map = std::move(retired_points_);
  res_.frames_refined = refinedTrajectory(res_.frames, res_.frame_anchors, res_.keyframe_maps);
  Trajectory aligned_frames;
  for (std::size_t i = 0; i < res_.frames_refined.size() && i < frame_ok_.size(); ++i)
    if (frame_ok_[i]) aligned_frames.push_back(res_.frames_refined[i]);
  res_.events_refined = smoothPoses(refinedTrajectory(res_.events, res_.event_anchors, res_.keyframe_maps),
                                    cfg_.event_smoothing_s);
  std::vector<TimeNs> intervals;
  for (std::size_t i = 1; i < aligned_frames.size(); ++i)
    intervals.push_back(aligned_frames[i].t - aligned_frames[i - 1].t);
  if (!intervals.empty()) {
    std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
    if (intervals[intervals.size() / 2] <= fromSeconds(cfg_.event_anchor_max_interval_s))
      res_.events_refined = anchorToFrames(res_.events_refined, aligned_frames,
                                           fromSeconds(cfg_.event_anchor_max_gap_s), segmentStartTimes(res_));
  }
}

void OdometryCore::pruneBuffered(TimeNs now) {
  // From the bootstrap's reference on, and up to buffered_before_reference_s before it (before there is
  // one: before the newest event frame).
  const std::vector<BootstrapFrame>& bf = boot_->frames();
  const TimeNs t_ref = boot_->hasReference() && !bf.empty() ? bf.front().t : now;
  const TimeNs t0 = t_ref - fromSeconds(cfg_.buffered_before_reference_s);
  std::erase_if(buffered_, [t0](const EventFrame& b) { return b.t < t0; });
}

// During the bootstrap the events track against its reference (its current inverse depths; 1 at
// first): their pose at the next frame is the bootstrap's hint (frames far apart: a constant-velocity
// guess is too far off). A new reference (a restart) is a new world: the tracking starts again.
void OdometryCore::syncBootstrapEvents(TimeNs t) {
  if (!cfg_.use_events || !boot_->hasReference()) return;
  const Keyframe& ref = boot_->reference();
  if (!boot_events_ || ref.t != boot_ref_t_ || boot_->restarts() != boot_restarts_) {
    boot_events_.emplace(und_.pinhole(), cfg_.events);
    boot_ref_t_ = ref.t, boot_restarts_ = boot_->restarts();
    has_boot_event_ = false;
  }
  boot_events_->setReference(ref, SE3());
  const BootstrapFrame& last = boot_->frames().back();
  if (last.t == t) boot_events_->correct(t, last.T_ref_c);
}

void OdometryCore::syncReference() {
  if (!cfg_.use_events || odo_->referenceVersion() == event_ref_version_ || odo_->reference().points.empty())
    return;
  // The events track against the keyframe's frame already (its provisional reference): a preliminary
  // reference of it would cost another point selection and depth fill for a few event frames.
  if (odo_->referencePreliminary() && events_->hasReference() &&
      events_->referenceId() == odo_->referenceId())
    return;
  events_->setReference(odo_->reference(), odo_->T_w_kf());
  event_ref_version_ = odo_->referenceVersion();
  // Published after its exposure ended (threaded back-end): the image deblurred meanwhile is kept.
  if (sharp_.t == odo_->reference().t) events_->sharpenReference(sharp_.t, sharp_.image);
}

void OdometryCore::exposureEnded(TimeNs t, TimeNs exposure, const cv::Mat& raw, const EventArray& events,
                                 std::size_t begin, std::size_t end) {
  if (!cfg_.use_events || !initialized_ || lost_ || !events_->hasReference() || events_->reference().t != t)
    return;
  const ScopedStage stage(&clock_, Stage::kFramePreparation);
  const cv::Mat sharp8 = deblurFrame(raw, events, begin, end, t, exposure, cfg_.deblur.contrast);
  und_.undistortImage(sharp8).convertTo(sharp_.image, CV_32F, 1.0 / 255.0);
  sharp_.t = t;
  events_->sharpenReference(t, sharp_.image);
}

// `bracket`: the frames before and after a buffered event frame (its start and motion prior).
void OdometryCore::trackEvents(const EventFrame& ef, const SE3* prior,
                               const std::function<bool(const SE3&)>& plausible,
                               const std::pair<const StampedPose*, const StampedPose*>& bracket) {
  const ScopedStage stage(&clock_, Stage::kEventTracking);
  const auto t0 = Clock::now();
  std::string why;
  const std::optional<SE3> T = bracket.first
                                   ? events_->trackBetween(ef, bracket.first->t, bracket.first->T_w_c,
                                                           bracket.second->t, bracket.second->T_w_c, &why)
                                   : events_->track(ef, prior, &why);
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
  res_.event_anchors.push_back({events_->referenceId(), events_->T_w_kf().inverse() * *T});
  res_.event_correlations.push_back(events_->lastCorrelation());
  if (events_->referenceId() != snapshot_ref_id_) snapshot(ef);
}

// Every stride-th keyframe's first event frame; at kMax, every other one goes and the stride doubles.
void OdometryCore::snapshot(const EventFrame& ef) {
  snapshot_ref_id_ = events_->referenceId();
  if (snapshot_refs_++ % snapshot_stride_ != 0) return;
  auto& shots = res_.event_snapshots;
  shots.push_back(
      {ef.t, snapshot_ref_id_, events_->lastCorrelation(), ef.delta.clone(), events_->lastPrediction()});
  if (shots.size() < EventFrameSnapshot::kMax) return;
  for (std::size_t i = 1; 2 * i < shots.size(); ++i) shots[i] = std::move(shots[2 * i]);
  shots.resize((shots.size() + 1) / 2);
  snapshot_stride_ *= 2;
}

}  // namespace eds
