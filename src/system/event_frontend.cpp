#include "system/event_frontend.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "core/image_sampling.hpp"
#include "core/log.hpp"

namespace eds {

namespace {

// The reference's points at (u, v) with inverse depths `depth` (median-filtered over radius_px when
// > 0), their gradients from the keyframe's image.
void addPoints(Keyframe& kf, std::vector<cv::Point2f>& uv, std::vector<double>& depth, double radius_px) {
  if (radius_px > 0) medianFilterInverseDepth(uv, depth, radius_px);
  kf.points.reserve(kf.points.size() + uv.size());
  for (std::size_t i = 0; i < uv.size(); ++i) {
    KeyframePoint kp;
    kp.u = uv[i].x, kp.v = uv[i].y;
    kp.gx = sampleBilinear(kf.grad_x, kp.u, kp.v);
    kp.gy = sampleBilinear(kf.grad_y, kp.u, kp.v);
    kp.inv_depth = depth[i];
    kf.points.push_back(kp);
  }
}

double medianDepth(const std::vector<KeyframePoint>& points) {
  std::vector<double> z;
  z.reserve(points.size());
  for (const KeyframePoint& p : points) z.push_back(1.0 / p.inv_depth);
  std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
  return z[z.size() / 2];
}

// The reference's image (and its gradients) at pose T_w_kf, without points.
Keyframe imageOf(const Keyframe& ref, const SE3& T_w_kf) {
  Keyframe kf;
  kf.id = ref.id;
  kf.t = ref.t;
  kf.T_w_kf = T_w_kf;
  setKeyframeImage(kf, ref.image);
  return kf;
}

template <std::size_t N>
double medianOf(std::array<double, N> v, std::size_t n) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n / 2),
                   v.begin() + static_cast<std::ptrdiff_t>(n));
  return v[n / 2];
}

}  // namespace

void LostTrackConfig::validate() const {
  if (!(min_correlation_ratio >= 0 && min_correlation_ratio < 1))
    throw std::invalid_argument("events.lost_track.min_correlation_ratio must be in [0, 1) (0: no check)");
  if (!(max_cost_ratio == 0 || max_cost_ratio > 1))
    throw std::invalid_argument("events.lost_track.max_cost_ratio must be 0 (no check) or > 1");
}

void PointBudgetConfig::validate() const {
  if (!(points_per_second >= 0) || !(max_frame_gap_s > 0))
    throw std::invalid_argument(
        "events.point_budget: points_per_second must be >= 0 (0: every point), max_frame_gap_s > 0");
}

void PersistentOutlierConfig::validate() const {
  if (frames < 0 || frames > 255 || !(sigmas > 0) || !(min_frame_gap_s >= 0))
    throw std::invalid_argument(
        "events.persistent_outliers: frames must be in [0, 255] (0: off), sigmas > 0, min_frame_gap_s >= 0");
}

void MotionPriorConfig::validate() const {
  if (!(sigma_translation > 0) || !(sigma_rotation > 0) || !(accel >= 0) || !(ang_accel >= 0) ||
      !(max_gap_s > 0))
    throw std::invalid_argument(
        "events.motion_prior: sigma_translation and sigma_rotation must be > 0, accel and ang_accel >= 0, "
        "max_gap_s > 0");
}

EventFrontend::EventFrontend(const CameraModel& pinhole, EventFrontendConfig cfg)
    : cam_(pinhole), cfg_(cfg), tracker_(pinhole, cfg.tracker) {
  cfg_.points.validate();
  cfg_.motion_prior.validate();
  cfg_.lost_track.validate();
  cfg_.point_budget.validate();
  cfg_.persistent_outliers.validate();
}

bool EventFrontend::framesSparse(TimeNs t) const {
  const double gap = cfg_.persistent_outliers.min_frame_gap_s;
  if (t_u1_ < 0 || toSeconds(t - t_u1_) > gap) return true;
  return t_u0_ >= 0 && toSeconds(t_u1_ - t_u0_) > gap;
}

int EventFrontend::maxReferencePoints() const {
  const PointBudgetConfig& pb = cfg_.point_budget;
  if (pb.points_per_second <= 0 || ef_count_ < kRateWindow) return 0;
  if (t_u0_ < 0 || t_u1_ <= t_u0_ || toSeconds(t_u1_ - t_u0_) > pb.max_frame_gap_s) return 0;
  const TimeNs newest = ef_times_[(ef_count_ - 1) % kRateWindow], oldest = ef_times_[ef_count_ % kRateWindow];
  if (newest <= oldest) return 0;
  const double rate = static_cast<double>(kRateWindow - 1) / toSeconds(newest - oldest);
  return static_cast<int>(std::max(1.0, std::floor(pb.points_per_second / rate)));
}

void EventFrontend::setTrackerReference() {
  const int max_points = maxReferencePoints();
  tracker_.setKeyframe(ref_, max_points);
  thinned_ = max_points > 0;
}

void EventFrontend::setReference(const Keyframe& ref, const SE3& T_w_kf) {
  if (provisional_t_ >= 0 && ref.t < provisional_t_) return;  // older than the frame tracked against
  Keyframe kf = imageOf(ref, T_w_kf);
  addFilledPoints(kf, ref.points);
  if (adopt(std::move(kf), T_w_kf)) ref_source_ = ref.points;
}

void EventFrontend::setProvisionalReference(int id, TimeNs t, const cv::Mat& img, const SE3& T_w_f,
                                            const std::vector<KeyframePoint>& points) {
  Keyframe kf;
  kf.id = id;
  kf.t = t;
  kf.T_w_kf = T_w_f;
  setKeyframeImage(kf, img);
  addFilledPoints(kf, points);
  if (adopt(std::move(kf), T_w_f, true)) ref_source_ = points;
}

void EventFrontend::sharpenReference(TimeNs t, const cv::Mat& img) {
  if (!has_ref_ || ref_.t != t || ref_source_.empty()) return;
  Keyframe kf;
  kf.id = ref_.id;
  kf.t = ref_.t;
  kf.T_w_kf = ref_.T_w_kf;
  setKeyframeImage(kf, img);
  addFilledPoints(kf, ref_source_);
  if (kf.points.size() < 50) return;
  median_depth_ = medianDepth(kf.points);
  ref_ = std::move(kf);
  setTrackerReference();
}

void EventFrontend::addFilledPoints(Keyframe& kf, const std::vector<KeyframePoint>& points) const {
  // The back-end's points (their depth is optimized), and the keyframe's selected pixels that lie
  // next to one of them (fill radius): farther, a depth taken across an occlusion edge would bias
  // the tracker.
  std::vector<ProjectedPoint> proj;
  for (const KeyframePoint& p : points)
    if (p.inv_depth > 0) proj.push_back({p.u, p.v, p.inv_depth});
  const std::vector<cv::Point> px = selectPoints(kf.grad_x, kf.grad_y, cfg_.points);
  const std::vector<double> rho = fillInverseDepth(px, proj, cfg_.fill);
  std::vector<cv::Point2f> uv;
  std::vector<double> depth;
  const float border = 2.0f;
  for (const ProjectedPoint& p : proj)
    if (p.u >= border && p.v >= border && p.u <= kf.image.cols - 1 - border &&
        p.v <= kf.image.rows - 1 - border)
      uv.emplace_back(p.u, p.v), depth.push_back(p.inv_depth);
  for (std::size_t i = 0; i < px.size(); ++i)
    if (rho[i] > 0)
      uv.emplace_back(static_cast<float>(px[i].x), static_cast<float>(px[i].y)), depth.push_back(rho[i]);
  addPoints(kf, uv, depth, cfg_.depth_median_px);
}

void EventFrontend::setDenseReference(const Keyframe& ref, const SE3& T_w_kf) {
  Keyframe kf = imageOf(ref, T_w_kf);
  std::vector<cv::Point2f> uv;
  std::vector<double> depth;
  for (const KeyframePoint& p : ref.points)
    if (p.inv_depth > 0) uv.emplace_back(p.u, p.v), depth.push_back(p.inv_depth);
  addPoints(kf, uv, depth, cfg_.depth_median_px);
  if (adopt(std::move(kf), T_w_kf)) ref_source_.clear();  // its points are not filled: no sharpening
}

bool EventFrontend::adopt(Keyframe kf, const SE3& T_w_kf, bool provisional) {
  if (kf.points.size() < 50) return false;  // keep the previous reference: it cannot be tracked against
  median_depth_ = medianDepth(kf.points);
  // The current estimate and the velocity, moved to the new keyframe.
  if (has_ref_) {
    // A keyframe made from a corrected frame comes back from the bundle adjustment in a moved world
    // (a threaded back-end publishes it after later event frames): the estimate and the frames' poses
    // follow that move, so that the keyframe is where its frame was tracked relative to them. The
    // provisional reference's move is known whatever frames came since: its own pose's.
    const std::optional<SE3> T_new_old = provisional_t_ >= 0 && kf.t == provisional_t_
                                             ? moveWorld(T_w_kf * T_w_kf_.inverse())
                                             : worldMoveTo(kf.t, T_w_kf);
    const SE3 T_w_old = T_new_old ? *T_new_old * T_w_kf_ : T_w_kf_;  // the old reference, moved
    const SE3 T_w_ef = T_w_old * T_ef_kf_.inverse();
    const Mat3 R = (T_w_kf.inverse() * T_w_old).rotationMatrix();  // old keyframe -> new
    T_ef_kf_ = T_w_ef.inverse() * T_w_kf;
    nu_.head<3>() = R * nu_.head<3>();
    nu_.tail<3>() = R * nu_.tail<3>();
  } else {
    T_ef_kf_ = SE3();
  }
  logf(LogLevel::kDebug, "[events] reference %d at %.3f%s: %zu points", kf.id, toSeconds(kf.t),
       provisional ? " (provisional)" : "", kf.points.size());
  T_w_kf_ = T_w_kf;
  ref_id_ = kf.id;
  provisional_t_ = provisional ? kf.t : -1;
  ref_ = std::move(kf);
  setTrackerReference();
  t_prev_ = -1;
  has_ref_ = true;
  recent_n_ = 0;
  return true;
}

std::optional<SE3> EventFrontend::track(const EventFrame& ef, const SE3* prior, std::string* failure) {
  if (!has_ref_) return std::nullopt;
  SE3 T_init = T_ef_kf_;
  if (prior) {
    T_init = prior->inverse() * T_w_kf_;
  } else if (t_prev_ >= 0 && t_last_ > t_prev_) {
    const double s = static_cast<double>(ef.t - t_last_) / static_cast<double>(t_last_ - t_prev_);
    const SE3 T_step = T_ef_kf_ * T_prev_.inverse();
    T_init = SE3::exp(std::clamp(s, 0.0, 3.0) * T_step.log()) * T_ef_kf_;
  }
  PosePrior motion;
  const bool use_motion = !prior && motionPrior(ef.t, motion);
  // Coarse-to-fine only when the prediction is weak: the first frames on a reference, or after three or
  // more event frames passed over (load shedding), where the constant-velocity prediction spans four
  // steps or more. A frame's correction, or that prediction over fewer steps, is close enough for the
  // finest level alone.
  const bool long_step = ef.passed_before >= kPassedForCoarseToFine;
  const int levels = !prior && !long_step && (t_prev_ >= 0 || corrected_) ? 1 : 0;
  corrected_ = false;
  return solve(ef, T_init, levels, use_motion ? &motion : nullptr, failure);
}

std::optional<SE3> EventFrontend::trackBetween(const EventFrame& ef, TimeNs t_a, const SE3& T_w_a, TimeNs t_b,
                                               const SE3& T_w_b, std::string* failure) {
  if (!has_ref_) return std::nullopt;
  const double span = toSeconds(t_b - t_a);
  const double s = span > 0 ? std::clamp(toSeconds(ef.t - t_a) / span, 0.0, 1.0) : 0.0;
  const SE3 T_w_pred = T_w_a * SE3::exp(s * (T_w_a.inverse() * T_w_b).log());
  PosePrior motion;
  motion.T_ef_kf = T_w_pred.inverse() * T_w_kf_;
  const MotionPriorConfig& mc = cfg_.motion_prior;
  // Both ends are measured: the interpolation's own error is the acceleration's, largest midway.
  motion.sigma = priorSigma(std::sqrt(s * (1 - s)) * span, 1.0);
  // The solve starts from the last event frame's pose when that lies between the same frames, else
  // from the nearer frame's: where the camera swings or starts from rest between frames a second
  // apart, the interpolation is far from either; the prior still pulls towards the interpolation.
  const bool from_last = !corrected_ && t_last_ >= t_a && t_last_ < ef.t;
  corrected_ = false;
  // Frames farther apart than max_gap_s say too little about the motion in between (as in track()).
  const bool use_motion = mc.enabled && span <= mc.max_gap_s;
  const SE3 T_w_near = s <= 0.5 ? T_w_a : T_w_b;
  return solve(ef, from_last ? T_ef_kf_ : T_w_near.inverse() * T_w_kf_, 0, use_motion ? &motion : nullptr,
               failure);
}

std::optional<SE3> EventFrontend::solve(const EventFrame& ef, const SE3& T_init, int levels,
                                        const PosePrior* motion, std::string* failure) {
  SE3 T = T_init;
  Vec6 nu = nu_;
  ef_times_[ef_count_++ % kRateWindow] = ef.t;
  // A thinned reference that usable frames stopped renewing (a dark stretch, frames lost) carries the
  // pose alone from here: all of its points again.
  if (thinned_ && (t_u1_ < 0 || toSeconds(ef.t - t_u1_) > cfg_.point_budget.max_frame_gap_s)) {
    tracker_.setKeyframe(ref_);
    thinned_ = false;
  }
  const PersistentOutlierConfig& po = cfg_.persistent_outliers;
  tracker_.setPersistentOutliers(framesSparse(ef.t) ? po.frames : 0, po.sigmas);
  const TrackResult tr = tracker_.track(ef, T, nu, levels, motion);
  last_correlation_ = tr.correlation;
  if (logEnabled(LogLevel::kDebug)) {
    const Vec6 dev = motion ? Vec6((T * motion->T_ef_kf.inverse()).log()) : Vec6::Zero();
    logf(LogLevel::kDebug,
         "[events] t %.3f corr %.3f it %d pts %d prior %d sigma_t %.4f dev_t %.4f dev_r %.4f "
         "init_dev_t %.4f left_out %d",
         toSeconds(ef.t), tr.correlation, tr.iterations, tr.points_in_view, motion != nullptr,
         motion ? motion->sigma[0] : 0.0, dev.head<3>().norm(), dev.tail<3>().norm(),
         (T * T_init.inverse()).translation().norm(), tracker_.numPersistentOutliers());
  }
  if (!tr.ok) {
    if (failure) *failure = tr.failure;
    return std::nullopt;
  }
  // A lost track's pose is not given out, but the estimate follows it: frozen at the last good pose
  // it would fall behind the camera until a frame or a new reference corrects it.
  const std::string lost = lostTrack(tr);
  if (lost.empty()) {
    recent_corr_[recent_n_ % kRecent] = tr.correlation;
    recent_cost_[recent_n_ % kRecent] = tr.cost;
    ++recent_n_;
  }
  last_in_view_ = tr.points_in_view;
  T_prev_ = T_ef_kf_;
  t_prev_ = t_last_;
  T_ef_kf_ = T;
  nu_ = nu;
  t_last_ = ef.t;
  if (!lost.empty()) {
    if (failure) *failure = lost;
    return std::nullopt;
  }
  return T_w_kf_ * T_ef_kf_.inverse();
}

// The tracker's own failure, or correlation far below / cost far above their recent level on this
// reference (from the third event frame on it).
std::string EventFrontend::lostTrack(const TrackResult& tr) const {
  if (recent_n_ < 3) return {};
  const std::size_t n = std::min(recent_n_, kRecent);
  const LostTrackConfig& lc = cfg_.lost_track;
  const double corr_ref = medianOf(recent_corr_, n), cost_ref = medianOf(recent_cost_, n);
  char why[160] = "";
  if (lc.min_correlation_ratio > 0 && tr.correlation < lc.min_correlation_ratio * corr_ref)
    std::snprintf(why, sizeof why, "correlation %.3f fell below %.2f of its recent median %.3f",
                  tr.correlation, lc.min_correlation_ratio, corr_ref);
  else if (lc.max_cost_ratio > 0 && tr.cost > lc.max_cost_ratio * cost_ref)
    std::snprintf(why, sizeof why, "cost %.4g rose above %.2f times its recent median %.4g", tr.cost,
                  lc.max_cost_ratio, cost_ref);
  return why;
}

void EventFrontend::correct(TimeNs t, const SE3& T_w_c, bool usable) {
  if (!has_ref_) return;
  if (usable) t_u0_ = t_u1_, t_u1_ = t;
  T_ef_kf_ = T_w_c.inverse() * T_w_kf_;
  t_last_ = t;
  t_prev_ = -1;
  corrected_ = true;
  t_f0_ = t_f1_, T_w_f0_ = T_w_f1_;
  t_f1_ = t, T_w_f1_ = T_w_c;
}

std::optional<SE3> EventFrontend::worldMoveTo(TimeNs t_kf, const SE3& T_w_kf) {
  // Exactly the frame's pose (a synchronous back-end returns the keyframe's optimized pose as the
  // frame's): no move, and no rounding either.
  const auto same = [&](const SE3& T) {
    return T.translation() == T_w_kf.translation() && T.quaternion().coeffs() == T_w_kf.quaternion().coeffs();
  };
  SE3 T_new_old;
  if (t_kf == t_f1_ && !same(T_w_f1_))
    T_new_old = T_w_kf * T_w_f1_.inverse();
  else if (t_kf == t_f0_ && t_kf != t_f1_ && !same(T_w_f0_))
    T_new_old = T_w_kf * T_w_f0_.inverse();
  else
    return std::nullopt;
  return moveWorld(T_new_old);
}

SE3 EventFrontend::moveWorld(const SE3& T_new_old) {
  T_w_f0_ = T_new_old * T_w_f0_;
  T_w_f1_ = T_new_old * T_w_f1_;
  return T_new_old;
}

bool EventFrontend::motionPrior(TimeNs t, PosePrior& prior) const {
  const MotionPriorConfig& mc = cfg_.motion_prior;
  if (!mc.enabled || t_f0_ < 0 || t_f1_ <= t_f0_) return false;
  const double gap = toSeconds(t_f1_ - t_f0_), dt = std::abs(toSeconds(t - t_f1_));
  if (gap > mc.max_gap_s || dt > mc.max_gap_s) return false;
  // Constant velocity in the body frame: s = 0 at the last frame, -1 at the one before.
  const double s = toSeconds(t - t_f1_) / gap;
  const SE3 T_w_pred = T_w_f1_ * SE3::exp(s * (T_w_f0_.inverse() * T_w_f1_).log());
  prior.T_ef_kf = T_w_pred.inverse() * T_w_kf_;
  prior.sigma = priorSigma(dt, 1.0 + std::sqrt(2.0) * dt / gap);
  return true;
}

Vec6 EventFrontend::priorSigma(double dt, double grow) const {
  const MotionPriorConfig& mc = cfg_.motion_prior;
  const double st = median_depth_ * (mc.sigma_translation * grow + 0.5 * mc.accel * dt * dt);
  const double sr = mc.sigma_rotation * grow + 0.5 * mc.ang_accel * dt * dt;
  Vec6 sigma;
  sigma << st, st, st, sr, sr, sr;
  return sigma;
}

}  // namespace eds
