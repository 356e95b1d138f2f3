#include "system/frame_frontend.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "core/log.hpp"
#include "mapping/depth_fill.hpp"
#include "system/run_stats.hpp"

namespace eds {

Flow flowOf(const std::vector<KeyframePoint>& pts, const SE3& T_f_kf, const CameraModel& cam) {
  Flow f;
  const Mat3 R = T_f_kf.rotationMatrix();
  const Vec3 t = T_f_kf.translation();
  double ss_rt = 0, ss_t = 0;
  int n = 0, in = 0;
  for (const KeyframePoint& p : pts) {
    if (!(p.inv_depth > 0)) continue;
    const Vec3 x = cam.pinholeRay(p.u, p.v);
    const Vec3 q_rt = R * x + t * p.inv_depth, q_t = x + t * p.inv_depth;  // scaled by ρ
    ++n;
    if (q_rt.z() <= 1e-9 || q_t.z() <= 1e-9) continue;
    const double u = cam.fx * q_rt.x() / q_rt.z() + cam.cx, v = cam.fy * q_rt.y() / q_rt.z() + cam.cy;
    const double ut = cam.fx * q_t.x() / q_t.z() + cam.cx, vt = cam.fy * q_t.y() / q_t.z() + cam.cy;
    ss_rt += (u - p.u) * (u - p.u) + (v - p.v) * (v - p.v);
    ss_t += (ut - p.u) * (ut - p.u) + (vt - p.v) * (vt - p.v);
    in += u >= 0 && v >= 0 && u <= cam.width - 1 && v <= cam.height - 1;
  }
  if (n == 0) return f;
  f.rt = std::sqrt(ss_rt / n), f.t = std::sqrt(ss_t / n), f.in_view = static_cast<double>(in) / n;
  return f;
}

namespace {
// 90th over 10th percentile of the points' depths: how much depth the view has.
double depthRatio(const std::vector<KeyframePoint>& pts) {
  std::vector<double> inv;
  for (const KeyframePoint& p : pts)
    if (p.inv_depth > 0) inv.push_back(p.inv_depth);
  if (inv.size() < 10) return 1.0;
  std::sort(inv.begin(), inv.end());
  return inv[inv.size() * 9 / 10] / inv[inv.size() / 10];
}

double medianInvDepth(const std::vector<KeyframePoint>& pts) {
  std::vector<double> inv;
  for (const KeyframePoint& p : pts)
    if (p.inv_depth > 0) inv.push_back(p.inv_depth);
  if (inv.empty()) return 1.0;
  std::nth_element(inv.begin(), inv.begin() + inv.size() / 2, inv.end());
  return inv[inv.size() / 2];
}
}  // namespace

FrameFrontend::FrameFrontend(const CameraModel& cam, const OdometryConfig& cfg, OdometryResult& res,
                             StageClock* clock, int first_keyframe_id)
    : cam_(cam),
      cfg_(cfg),
      res_(res),
      worker_(cam, cfg.mapping, cfg.backend, cfg.threaded_backend, clock, first_keyframe_id,
              cfg.wait_for_keyframe && cfg.early_reference && cfg.use_events),
      tracker_(cam, cfg.frame_tracker) {}

SE3 FrameFrontend::addKeyframe(TimeNs t, const cv::Mat& img, const SE3& T_w_new, double a, double b,
                               std::vector<KeyframePoint> pts_with_depth) {
  const int id = worker_.submit({t, img, T_w_new, a, b, std::move(pts_with_depth)});
  if (cfg_.threaded_backend) {
    setPending(id, t, T_w_new, a);
    return T_w_new;
  }
  adoptReference(false);
  return T_w_kf_;
}

void FrameFrontend::awaitPendingKeyframe(bool adjusted) {
  // Adjusted: also the keyframe whose preliminary reference an event frame took up meanwhile.
  const bool pending = pending_.active || (adjusted && ref_preliminary_);
  const bool wait = !has_ref_ || (pending && cfg_.wait_for_keyframe);
  if (wait && cfg_.threaded_backend && worker_.busy()) ++res_.backend_waits;
  if (wait && has_ref_ && !adjusted) worker_.waitMapped();
  adoptReference(wait && (adjusted || !has_ref_));
}

SE3 FrameFrontend::track(TimeNs t, const cv::Mat& img, const SE3* prior) {
  awaitPendingKeyframe();
  const auto t0 = Clock::now();
  SE3 T_f_kf;
  double alpha = 1, beta = 0;
  FrameTrackResult tr = align(t, img, prior, T_f_kf, alpha, beta);
  Flow fl;
  bool new_kf;
  if (pending_.active) {
    // Motion since the keyframe the back-end is working on.
    const SE3 T_f_pending = (T_w_kf_ * T_f_kf.inverse()).inverse() * pending_.T_w_kf;
    fl = flowOf(pending_.points, T_f_pending, cam_);
    new_kf = wantKeyframe(fl, alpha * std::exp(a_kf_ - pending_.a));
  } else {
    fl = flowOf(ref_.points, T_f_kf, cam_);
    new_kf = wantKeyframe(fl, alpha);
    // A keyframe taken ahead of need waits for nothing: while the back-end is busy, the next frame
    // decides again.
    if (!new_kf && !worker_.busy()) new_kf = keyframeDueBeforeNextFrame(T_f_kf);
  }
  if (new_kf && worker_.busy() && !cfg_.wait_for_keyframe &&
      !wantKeyframe(flowOf(ref_.points, T_f_kf, cam_), alpha, kDeferLimit)) {
    // A live camera cannot wait for the back-end: tracking goes on against the current reference and
    // the next frame decides again, as long as the frame is not far from that reference.
    new_kf = false;
    ++res_.keyframes_deferred;
  } else if (new_kf && worker_.busy()) {
    ++res_.backend_waits;
    // The back-end is still mapping the previous keyframe: wait for it (so that an offline run cannot
    // run away from its map), take the new reference and track again against it.
    adoptReference(true);
    tr = align(t, img, prior, T_f_kf, alpha, beta);
    fl = flowOf(ref_.points, T_f_kf, cam_);
    new_kf = wantKeyframe(fl, alpha) || keyframeDueBeforeNextFrame(T_f_kf);
  }
  res_.track_ms.push_back(msSince(t0));
  last_ok_ = tr.ok;
  res_.feature_starts += from_features_;
  if (tr.ok) {
    ++res_.tracked;
  } else {
    res_.failures.push_back({t, "frame alignment failed (rmse " + std::to_string(tr.rmse) + ", " +
                                    std::to_string(tr.residuals) + " residuals)"});
    if (!(alpha > 0)) alpha = alpha_, beta = beta_;
  }
  const SE3 T_w_f = T_w_kf_ * T_f_kf.inverse();
  // α, β relate the frame to the keyframe (I_f = α I_kf + β); the window's per-frame (a, b) are
  // absolute: α = e^{a_f − a_kf}, β = b_f − α b_kf.
  a_last_ = a_kf_ + std::log(alpha), b_last_ = beta + alpha * b_kf_;
  alpha_ = alpha, beta_ = beta;
  SE3 T_w_out = T_w_f;
  if (new_kf && tr.ok) T_w_out = addKeyframe(t, img, T_w_f, a_last_, b_last_);
  setLast(t, T_w_out);
  return T_w_out;
}

std::optional<SE3> FrameFrontend::trackRefused(TimeNs t, const cv::Mat& img, const SE3* prior) {
  // No usable frame aligned since the map (or its relocalization) began: nothing to compare with.
  if (!has_ref_ || !has_last_ || last_residuals_ == 0) return std::nullopt;
  const SE3 T_w_start = prior ? *prior : constantVelocityPose(t);
  SE3 T_f_kf = T_w_start.inverse() * T_w_kf_;
  double alpha = 1, beta = 0;
  const FrameTrackResult tr = tracker_.track(img, T_f_kf, alpha, beta, cfg_.prior_levels);
  const SE3 T_w_f = T_w_kf_ * T_f_kf.inverse();
  const SE3 T_start_f = T_w_start.inverse() * T_w_f;
  const FrameQualityConfig& q = cfg_.frame_quality;
  logf(LogLevel::kDebug,
       "refused frame %.3f: %d residuals, rmse %.4f, %.3f cm / %.3f deg from its start (%s)", toSeconds(t),
       tr.residuals, tr.rmse, 100 * T_start_f.translation().norm(), T_start_f.so3().angle() * 180 / M_PI,
       prior ? "events" : "constant velocity");
  if (!tr.ok || tr.residuals < q.refused_min_residuals * last_residuals_ ||
      T_start_f.translation().norm() > q.refused_max_shift / medianInvDepth(ref_.points) ||
      T_start_f.so3().angle() > q.refused_max_turn_deg * M_PI / 180.0)
    return std::nullopt;
  ++res_.tracked;
  setLast(t, T_w_f);
  return T_w_f;
}

std::optional<SE3> FrameFrontend::relocalize(TimeNs t, const cv::Mat& img, std::string& found) {
  adoptReference(cfg_.threaded_backend);
  if (!has_ref_) {
    found = "no reference to relocalize against";
    return std::nullopt;
  }
  const Relocalization r = eds::relocalize(ref_, img, cam_, cfg_.recovery.relocalizer);
  if (!r.ok) {
    found = std::to_string(r.inliers) + " of " + std::to_string(r.matches) +
            " feature matches with keyframe " + std::to_string(ref_id_) + " agree on a pose: too few";
    return std::nullopt;
  }
  SE3 T_f_kf = r.T_f_kf;
  double alpha = alpha_, beta = beta_;
  const FrameTrackResult tr = tracker_.track(img, T_f_kf, alpha, beta, 0);
  // How far the alignment moved the features' pose, relative to the scene's depth.
  const double moved = (T_f_kf * r.T_f_kf.inverse()).translation().norm() * medianInvDepth(ref_.points);
  if (!tr.ok || moved > cfg_.recovery.max_refinement) {
    found = "the alignment from the features' pose (" + std::to_string(r.inliers) + " of " +
            std::to_string(r.matches) + " matches) " + (tr.ok ? "moved too far" : "failed");
    return std::nullopt;
  }
  found = std::to_string(r.inliers) + " of " + std::to_string(r.matches) + " feature matches with keyframe " +
          std::to_string(ref_id_) + ", aligned to rmse " + std::to_string(tr.rmse);
  alpha_ = alpha, beta_ = beta;
  last_rmse_ = tr.rmse, last_residuals_ = tr.residuals;
  has_last_ = has_prev_ = false;  // at rest: the velocity before the loss means nothing now
  setLast(t, T_w_kf_ * T_f_kf.inverse());
  return last_T_w_f_;
}

SE3 FrameFrontend::constantVelocityPose(TimeNs t) const {
  if (!has_prev_ || last_t_ <= prev_t_) return last_T_w_f_;
  const SE3 step = prev_T_w_f_.inverse() * last_T_w_f_;
  // Frames evenly spaced: one step, exactly. Otherwise the step scaled to the time since the last frame
  // (frames dropped, or taken irregularly by a real-time consumer that is behind), at most kMaxCvSteps.
  if (t - last_t_ == last_t_ - prev_t_) return last_T_w_f_ * step;
  const double steps =
      std::clamp(static_cast<double>(t - last_t_) / static_cast<double>(last_t_ - prev_t_), 0.0, kMaxCvSteps);
  return last_T_w_f_ * SE3::exp(steps * step.log());
}

void FrameFrontend::setLast(TimeNs t, const SE3& T_w_f) {
  if (has_last_) prev_T_w_f_ = last_T_w_f_, prev_t_ = last_t_, has_prev_ = true;
  last_T_w_f_ = T_w_f, last_t_ = t;
  has_last_ = true;
}

bool FrameFrontend::adoptReference(bool wait) {
  if (wait) worker_.waitIdle();
  std::optional<TrackingReference> ref = worker_.takeReference();
  if (!ref) return false;
  T_w_kf_ = ref->kf.T_w_kf;
  a_kf_ = ref->a, b_kf_ = ref->b;
  ref_ = std::move(ref->kf);
  ref_id_ = ref->id;
  ++reference_version_;
  ref_preliminary_ = ref->preliminary;
  res_.early_references += ref->preliminary;
  pending_.active = false;
  has_ref_ = !ref_.points.empty();
  ref_depth_ratio_ = depthRatio(ref_.points);
  if (has_ref_) tracker_.setKeyframe(ref_);
  // The last frame's brightness, relative to the new reference.
  alpha_ = std::exp(a_last_ - a_kf_), beta_ = b_last_ - alpha_ * b_kf_;
  return true;
}

void FrameFrontend::setPending(int id, TimeNs t, const SE3& T_w_new, double a) {
  pending_.active = true;
  pending_.id = id;
  pending_.t = t;
  pending_.T_w_kf = T_w_new;
  pending_.a = a;
  pending_.points.clear();
  // The reference's points that the new keyframe sees, in its pixels (a stand-in for its own points,
  // which the back-end is still mapping).
  std::vector<Vec3> p_w;
  p_w.reserve(ref_.points.size());
  for (const KeyframePoint& p : ref_.points)
    if (p.inv_depth > 0) p_w.push_back(T_w_kf_ * (cam_.pinholeRay(p.u, p.v) / p.inv_depth));
  for (const ProjectedPoint& q : projectPoints(p_w, T_w_new, cam_)) {
    KeyframePoint kp;
    kp.u = q.u, kp.v = q.v, kp.inv_depth = q.inv_depth;
    pending_.points.push_back(kp);
  }
}

bool FrameFrontend::wantKeyframe(const Flow& fl, double alpha, double scale) const {
  const double wh = scale * (cam_.width + cam_.height);
  return fl.t > cfg_.policy.flow_t * wh || fl.rt > cfg_.policy.flow_rt * wh ||
         fl.in_view < cfg_.policy.min_in_view || std::abs(std::log(alpha)) > cfg_.policy.max_log_alpha;
}

bool FrameFrontend::keyframeDueBeforeNextFrame(const SE3& T_f_kf) const {
  const double f = cfg_.policy.lookahead;
  if (!cfg_.use_events || !(f > 0) || !has_last_) return false;
  // The events track against this keyframe until the next frame: at constant velocity (one more
  // step like the last one), would the policy want a keyframe there? Then take it now. At video rate
  // this moves a keyframe one frame earlier; with frames 0.2 s apart it keeps the keyframe from
  // ageing to 0.4 s, where occlusions and parallax on near objects break the event tracker.
  const SE3 T_w_f = T_w_kf_ * T_f_kf.inverse();
  const SE3 T_w_next = T_w_f * (last_T_w_f_.inverse() * T_w_f);
  const Flow fl = flowOf(ref_.points, T_w_next.inverse() * T_w_kf_, cam_);
  // Parallax only matters where the scene has depth: near objects slide over far ones, and the event
  // tracker cannot model what gets covered and uncovered. On a scene of one depth the extra keyframes
  // only shorten the window's baseline (ESIM at 5 Hz: 0.47 -> 0.60 cm).
  const bool deep = ref_depth_ratio_ >= cfg_.policy.lookahead_depth_ratio;
  return (deep && fl.t > f * cfg_.policy.flow_t * (cam_.width + cam_.height)) ||
         fl.in_view < cfg_.policy.min_in_view / f;
}

// Aligns the frame to the reference from the prior (the event pose) or a constant-velocity
// prediction, trying DSO's other starting points when that fails.
FrameTrackResult FrameFrontend::align(TimeNs t, const cv::Mat& img, const SE3* prior, SE3& T_f_kf,
                                      double& alpha, double& beta) {
  from_features_ = false;
  const SE3 T_w_cv = constantVelocityPose(t);
  const SE3 T_w_pred = prior ? *prior : T_w_cv;
  T_f_kf = T_w_pred.inverse() * T_w_kf_;
  alpha = alpha_, beta = beta_;
  if (!has_ref_) return {};
  // The event tracker's pose is close: the coarse levels would only cost time.
  FrameTrackResult tr = tracker_.track(img, T_f_kf, alpha, beta, prior ? cfg_.prior_levels : 0);
  // Starting points to try as well: the frames' own constant-velocity prediction when the event pose
  // seeded the alignment (the event tracker can drift between frames: the frame must not follow it),
  // then, when the alignment failed, no motion since the last frame and half the velocity.
  // The routine second start (both alignments fine so far) needs the fine levels only, like the first.
  std::vector<std::pair<SE3, int>> others;  // start, pyramid levels (0: all)
  const bool usual = tr.ok && !(tr.rmse > 1.15 * last_rmse_);
  const double cv_distance = (T_w_cv.inverse() * (T_w_kf_ * T_f_kf.inverse())).log().norm();
  if (prior && ((cfg_.frame_always_tries_cv && cv_distance >= cfg_.frame_cv_min_distance) || !usual))
    others.emplace_back(T_w_cv, usual ? cfg_.prior_levels : 0);
  if (!tr.ok) {
    others.emplace_back(last_T_w_f_, 0);
    others.emplace_back(interpolateGeodesic(last_T_w_f_, T_w_pred, 0.5), 0);
  }
  for (const auto& [T_w_try, levels] : others) {
    SE3 T_try = T_w_try.inverse() * T_w_kf_;
    double a_try = alpha_, b_try = beta_;
    const FrameTrackResult tr2 = tracker_.track(img, T_try, a_try, b_try, levels);
    if ((tr2.ok && !tr.ok) || (tr2.ok == tr.ok && tr2.rmse < tr.rmse)) {
      T_f_kf = T_try, alpha = a_try, beta = b_try, tr = tr2;
    }
  }
  if (has_last_ && cfg_.feature_start.sparse(last_t_, t)) alignFromFeatures(t, img, tr, T_f_kf, alpha, beta);
  if (tr.ok) last_rmse_ = tr.rmse, last_residuals_ = tr.residuals;
  return tr;
}

bool featureAlignmentWins(const FrameTrackResult& features, const FrameTrackResult& best,
                          double max_rmse_ratio) {
  if (!features.ok) return false;
  if (!best.ok) return true;
  // A pose that sees much less of the reference fits its few points easily: no evidence either.
  return features.rmse < max_rmse_ratio * best.rmse &&
         features.residuals >= kFeatureMinResidualShare * best.residuals;
}

// Frames far apart: the events' pose may have drifted into a wrong minimum that the alignment then
// keeps, and a constant-velocity start means little after a second. ORB features matched to the
// reference give a start that owes nothing to either; its alignment replaces the others' only when it
// fits clearly better, since on a scene seen mostly from afar the features' translation is loose and
// a slightly lower residual there is no evidence.
void FrameFrontend::alignFromFeatures(TimeNs t, const cv::Mat& img, FrameTrackResult& tr, SE3& T_f_kf,
                                      double& alpha, double& beta) {
  const Relocalization r = eds::relocalize(ref_, img, cam_, cfg_.recovery.relocalizer);
  if (!r.ok) {
    logf(LogLevel::kDebug, "frame %.3f: %d of %d feature matches agree: too few to align from", toSeconds(t),
         r.inliers, r.matches);
    return;
  }
  SE3 T_try = r.T_f_kf;
  double a_try = alpha_, b_try = beta_;
  const FrameTrackResult tr2 = tracker_.track(img, T_try, a_try, b_try, 0);
  logf(LogLevel::kDebug,
       "frame %.3f: %d of %d feature matches agree; aligned from them: rmse %.4f over %d residuals (%s), "
       "against %.4f over %d",
       toSeconds(t), r.inliers, r.matches, tr2.rmse, tr2.residuals, tr2.ok ? "ok" : "failed", tr.rmse,
       tr.residuals);
  if (!featureAlignmentWins(tr2, tr, cfg_.feature_start.max_rmse_ratio)) return;
  T_f_kf = T_try, alpha = a_try, beta = b_try, tr = tr2;
  from_features_ = true;
}

}  // namespace eds
