#include "init/bootstrap.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <stdexcept>

#include "core/log.hpp"

namespace eds {

void BootstrapConfig::validate() const {
  points.validate();
  if (!(min_parallax_px > 0) || !(min_parallax_px_sparse > 0) || !(sparse_frame_interval_s > 0) ||
      min_points < 1 || min_frames < 1 || min_frames_sparse < 1 || max_frames <= min_frames ||
      !(max_rmse > 0) || !(max_rmse_growth > 1) || !(min_inlier_share > 0 && min_inlier_share <= 1) ||
      !(min_inlier_fraction_sparse >= 0 && min_inlier_fraction_sparse <= 1) || depth_prior_weight < 0 ||
      final_views < 2)
    throw std::invalid_argument("bootstrap: bad configuration");
  const FeatureMatchConfig& f = geometric_init.features;
  if (f.features < 8 || f.max_hamming < 0 || f.max_hamming > 256 || !(f.ratio > 0 && f.ratio <= 1))
    throw std::invalid_argument(
        "bootstrap.geometric_init.features: features must be >= 8 (an essential matrix needs 5 matches), "
        "max_hamming in [0, 256], ratio in (0, 1]");
  if (!(geometric_init.min_parallax_deg_matches >= 0) || !(geometric_init.features_min_interval_s >= 0))
    throw std::invalid_argument(
        "bootstrap.geometric_init: min_parallax_deg_matches and features_min_interval_s must be >= 0");
}

Bootstrap::Bootstrap(const CameraModel& pinhole, BootstrapConfig cfg)
    : cam_(pinhole), cfg_(cfg), geo_(pinhole, cfg.geometric_init) {
  cfg_.validate();
}

bool Bootstrap::setReference(TimeNs t, const cv::Mat& image) {
  Keyframe kf;
  kf.t = t;
  setKeyframeImage(kf, image);
  const std::vector<cv::Point> pts = selectPointsOnIntensity(kf.image, cfg_.points);
  for (const cv::Point& p : pts) {
    // Saturated or black pixels carry no usable photometric information (HDR sequences start black).
    const float I = kf.image.at<float>(p.y, p.x);
    if (I > cfg_.max_intensity || I < cfg_.min_intensity) continue;
    KeyframePoint kp;
    kp.u = static_cast<float>(p.x), kp.v = static_cast<float>(p.y);
    kp.gx = kf.grad_x.at<float>(p.y, p.x), kp.gy = kf.grad_y.at<float>(p.y, p.x);
    kp.inv_depth = 1.0;
    kf.points.push_back(kp);
  }
  frames_.clear();
  images_.clear();
  if (static_cast<int>(kf.points.size()) < cfg_.min_points) {
    has_ref_ = false;
    return false;
  }
  ref_ = std::move(kf);
  has_ref_ = true;
  parallax_ = 0;
  previous_rmse_ = 0, previous_inliers_ = 0;
  frames_.push_back({t, SE3(), 0.0, 0.0});
  images_.push_back(image);
  photometric_failed_ = false;
  geo_state_ = cfg_.geometric ? GeoState::kPending : GeoState::kUnavailable;
  if (cfg_.geometric) geo_.reset(image);
  return true;
}

double Bootstrap::translationParallax(const SE3& T_c_ref) const {
  const Mat3 R = T_c_ref.rotationMatrix();
  const Vec3 t = T_c_ref.translation();
  double ss = 0;
  int n = 0;
  for (const KeyframePoint& p : ref_.points) {
    if (!(p.inv_depth > 0)) continue;
    const Vec3 x = cam_.pinholeRay(p.u, p.v);
    const Vec3 q0 = R * x, q1 = q0 + t * p.inv_depth;  // same ray, scaled by ρ: no division by ρ
    if (q0.z() <= 1e-9 || q1.z() <= 1e-9) continue;
    const double du = cam_.fx * (q1.x() / q1.z() - q0.x() / q0.z());
    const double dv = cam_.fy * (q1.y() / q1.z() - q0.y() / q0.z());
    ss += du * du + dv * dv;
    ++n;
  }
  return n ? std::sqrt(ss / n) : 0.0;
}

// The geometric path on this frame; true when it initialized.
bool Bootstrap::tryGeometry(TimeNs t, const cv::Mat& image, const SE3* hint) {
  if (geo_state_ == GeoState::kUnavailable) return false;
  // The planar verdict holds for this frame only: a homography also explains a rotation-dominated
  // motion of a scene with depth (a hand-held camera shaking before it translates), and a verdict
  // taken then would let the constant-depth photometric path succeed on a 3D scene.
  geo_state_ = GeoState::kPending;
  const bool sparse = !frames_.empty() && t - frames_.back().t >= fromSeconds(cfg_.sparse_frame_interval_s);
  const double interval_s = frames_.empty() ? 0.0 : toSeconds(t - frames_.back().t);
  const std::optional<GeometricInitResult> g = geo_.add(image, sparse, hint, interval_s);
  if (g && g->planar) geo_state_ = GeoState::kPlanar;
  if (g && logEnabled(LogLevel::kDebug))
    logf(LogLevel::kDebug, "bootstrap: geometry at frame %zu: planar %d inliers %d parallax %.2f deg",
         frames_.size(), g->planar, g->inliers, g->parallax_deg);
  if (g && !g->planar && initFromGeometry(t, image, *g)) return true;
  // Tracks that only the events' pose or the features kept serve this frame alone: the photometric path
  // does not wait for them (the next frames' corners, tracked on from there, made weak late starts).
  if ((!g && geo_.tracks() < cfg_.geometric_init.min_tracks) || geo_.tracksReseeded())
    geo_state_ = GeoState::kUnavailable;
  return false;
}

// The frame aligned to the reference at constant depth, from the constant-velocity prediction and the
// events' hint (the better of the two), else from the last pose. False if every start failed.
bool Bootstrap::alignToReference(const cv::Mat& image, const SE3* hint, SE3& T_c_ref, double& alpha,
                                 double& beta) const {
  T_c_ref = frames_.back().T_ref_c.inverse();
  if (frames_.size() >= 2) {
    const SE3 T_last = frames_.back().T_ref_c.inverse(),
              T_prev = frames_[frames_.size() - 2].T_ref_c.inverse();
    T_c_ref = (T_last * T_prev.inverse()) * T_last;
  }
  alpha = std::exp(frames_.back().a), beta = frames_.back().b;
  FrameTracker tracker(cam_, cfg_.tracker);
  tracker.setKeyframe(ref_);
  // The two starts at once: before the first keyframe the back-end's core is free.
  SE3 T_h = hint ? *hint : SE3();
  double a_h = alpha, b_h = beta;
  std::future<FrameTrackResult> hinted;
  if (hint) hinted = std::async(std::launch::async, [&] { return tracker.track(image, T_h, a_h, b_h); });
  FrameTrackResult tr = tracker.track(image, T_c_ref, alpha, beta);
  if (hint) {
    const FrameTrackResult tr_h = hinted.get();
    if (tr_h.ok && a_h > 0 && (!tr.ok || !(alpha > 0) || tr_h.rmse < tr.rmse)) {
      T_c_ref = T_h, alpha = a_h, beta = b_h, tr = tr_h;
      if (logEnabled(LogLevel::kDebug))
        logf(LogLevel::kDebug, "bootstrap: the events' pose seeds frame %zu", frames_.size());
    }
  }
  if (tr.ok && alpha > 0) return true;
  // The prediction may have been the problem: retry from the last pose before giving up.
  T_c_ref = frames_.back().T_ref_c.inverse();
  alpha = std::exp(frames_.back().a), beta = frames_.back().b;
  return tracker.track(image, T_c_ref, alpha, beta).ok && alpha > 0;
}

// Two-frame photometric BA, pose and inverse depths together, coarse-to-fine: the same points on every
// pyramid level (their pattern spans more of the scene on coarse levels), so that depths far from the
// constant start (large motion between the first frames) come into the basin. fr[1] and pts hold the
// result.
BaStats Bootstrap::twoFrameBa(const cv::Mat& image, const SE3& T_c_ref, double alpha, double beta,
                              std::vector<BaFrame>& fr, std::vector<BaPoint>& pts) const {
  const FrameTracker tracker(cam_, cfg_.tracker);
  std::vector<cv::Mat> ref_pyr, cur_pyr;
  tracker.pyramid(ref_.image, ref_pyr);
  tracker.pyramid(image, cur_pyr);
  fr.assign(2, BaFrame{});
  fr[0].fixed = true;
  fr[1].T_w_c = T_c_ref.inverse();
  fr[1].a = std::log(alpha), fr[1].b = beta;
  pts.clear();
  pts.reserve(ref_.points.size());
  for (const KeyframePoint& p : ref_.points) {
    BaPoint bp;
    bp.host = 0;
    bp.inv_depth = p.inv_depth > 0 ? p.inv_depth : 1.0;
    bp.targets = {1};
    bp.prior_weight = cfg_.depth_prior_weight, bp.prior_inv_depth = 1.0;
    pts.push_back(bp);
  }
  BaStats st;
  for (int l = std::min<int>(cfg_.ba_levels, ref_pyr.size()) - 1; l >= 0; --l) {
    const double s = 1.0 / (1 << l);
    const CameraModel c = pyramidCamera(cam_, l);
    fr[0].image = ref_pyr[l];
    fr[1].image = cur_pyr[l];
    for (std::size_t i = 0; i < pts.size(); ++i) {
      pts[i].u = static_cast<float>((ref_.points[i].u + 0.5) * s - 0.5);
      pts[i].v = static_cast<float>((ref_.points[i].v + 0.5) * s - 0.5);
      pts[i].targets = {1};
      pts[i].outlier = false;
    }
    st = PhotometricBA(c, cfg_.ba).optimize(fr, pts);
  }
  return st;
}

bool Bootstrap::add(TimeNs t, const cv::Mat& image, const SE3* hint) {
  if (done_) throw std::logic_error("Bootstrap::add after initialization");
  last_image_ = image;
  if (!has_ref_) {
    setReference(t, image);
    return false;
  }
  if (tryGeometry(t, image, hint)) return true;
  if (photometric_failed_) return keepForGeometry(t, image);
  SE3 T_c_ref;
  double alpha = 1, beta = 0;
  if (!alignToReference(image, hint, T_c_ref, alpha, beta)) {
    photometric_failed_ = true;
    return keepForGeometry(t, image);
  }
  std::vector<BaFrame> fr;
  std::vector<BaPoint> pts;
  rmse_ = twoFrameBa(image, T_c_ref, alpha, beta, fr, pts).final_rmse;
  // Points that do not match (occluded, out of view) keep their depth but are marked unknown.
  int inliers = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ref_.points[i].inv_depth = pts[i].outlier ? 0.0 : pts[i].inv_depth;
    inliers += !pts[i].outlier;
  }
  T_c_ref = fr[1].T_w_c.inverse();
  frames_.push_back({t, fr[1].T_w_c, fr[1].a, fr[1].b});
  images_.push_back(image);
  const double previous_parallax = parallax_;
  parallax_ = translationParallax(T_c_ref);
  const bool diverged = parallax_ - previous_parallax > cfg_.max_parallax_step_px;

  const int n_after = static_cast<int>(frames_.size()) - 1;
  if (logEnabled(LogLevel::kDebug))
    logf(LogLevel::kDebug,
         "bootstrap: frame %d parallax %.2f px rmse %.4f inliers %d/%zu t %.3f %.3f %.3f a %.3f", n_after,
         parallax_, rmse_, inliers, pts.size(), fr[1].T_w_c.translation().x(), fr[1].T_w_c.translation().y(),
         fr[1].T_w_c.translation().z(), fr[1].a);
  const bool exposure_jump = !(std::abs(fr[1].a) <= cfg_.max_log_brightness);
  const bool worse_fit = previous_rmse_ > 0 && rmse_ > cfg_.max_rmse_growth * previous_rmse_ &&
                         inliers < cfg_.min_inlier_share * previous_inliers_;
  if (worse_fit)
    logf(LogLevel::kDebug, "bootstrap: frame %d fits worse than the one before (rmse %.4f, %d inliers)",
         n_after, previous_rmse_, previous_inliers_);
  // Between frames far apart a constant-depth fit that keeps few of the points as inliers explained a 3D
  // scene with a wrong pose (rooms at 2 FPS: a third kept, the translation 55-90 deg off).
  const bool sparse = t - frames_[frames_.size() - 2].t >= fromSeconds(cfg_.sparse_frame_interval_s);
  const bool few_inliers_sparse =
      sparse && inliers < cfg_.min_inlier_fraction_sparse * static_cast<double>(pts.size());
  if (diverged || exposure_jump || worse_fit || few_inliers_sparse || rmse_ > cfg_.max_rmse ||
      inliers < cfg_.min_points || n_after > cfg_.max_frames) {
    // The geometric path may still make it from this reference (large motion between sparse frames).
    frames_.pop_back();
    images_.pop_back();
    photometric_failed_ = true;
    return keepForGeometry(t, image);
  }
  previous_rmse_ = rmse_, previous_inliers_ = inliers;
  const double min_parallax = sparse ? cfg_.min_parallax_px_sparse : cfg_.min_parallax_px;
  const int min_frames = sparse ? cfg_.min_frames_sparse : cfg_.min_frames;
  if (n_after < min_frames || parallax_ < min_parallax || geo_state_ == GeoState::kPending) return false;
  // Each frame in between was fitted with the depths of its time, which moved on since (from 1 at the
  // start): aligned again to the final map, in its scale.
  realignFrames(t, frames_.back().T_ref_c, 1.0, frames_.size() - 1);
  refineWithViews(image);
  normalizeScale();
  done_ = true;
  return true;
}

bool Bootstrap::keepForGeometry(TimeNs t, const cv::Mat& image) {
  const bool geometry_alive =
      geo_state_ == GeoState::kPending && geo_.tracks() >= cfg_.geometric_init.min_tracks;
  if (!geometry_alive || static_cast<int>(frames_.size()) > cfg_.max_frames) {
    ++restarts_;
    setReference(t, image);
    return false;
  }
  // The photometric path gave up on this reference: the frame keeps the last pose as a placeholder
  // (the geometric path re-aligns every frame once it succeeds).
  frames_.push_back({t, frames_.back().T_ref_c, frames_.back().a, frames_.back().b});
  images_.push_back(image);
  return false;
}

void Bootstrap::normalizeScale() {
  // Success: mean inverse depth 1, translations scaled to match (depths × m, so translations × m).
  double sum = 0;
  int n = 0;
  for (const KeyframePoint& p : ref_.points)
    if (p.inv_depth > 0) sum += p.inv_depth, ++n;
  const double m = sum / n;
  for (KeyframePoint& p : ref_.points) p.inv_depth /= m;
  for (BootstrapFrame& f : frames_) f.T_ref_c.translation() *= m;
  images_ = {};
}

void Bootstrap::realignFrames(TimeNs t_last, const SE3& T_ref_last, double scale, std::size_t count,
                              const std::vector<std::optional<SE3>>& T_ref_c_tracks) {
  // Starting points: the previous frame's result moved by the relative motion the frames had before
  // (translation times `scale`), the geodesic between the reference and the last frame, and the pose
  // the corner tracks give (where there is one); the best fit wins.
  FrameTracker tracker(cam_, cfg_.tracker);
  tracker.setKeyframe(ref_);
  const double span = static_cast<double>(t_last - frames_.front().t);
  const std::vector<BootstrapFrame> before(frames_.begin(), frames_.begin() + count);
  SE3 T_prev_result;  // reference (k = 0): identity
  for (std::size_t k = 1; k < count; ++k) {
    SE3 step = before[k - 1].T_ref_c.inverse() * before[k].T_ref_c;
    step.translation() *= scale;
    std::vector<SE3> starts = {
        (T_prev_result * step).inverse(),
        interpolateGeodesic(SE3(), T_ref_last, static_cast<double>(frames_[k].t - frames_.front().t) / span)
            .inverse()};
    if (k - 1 < T_ref_c_tracks.size() && T_ref_c_tracks[k - 1])
      starts.push_back(T_ref_c_tracks[k - 1]->inverse());
    alignFromStarts(tracker, k, starts);
    T_prev_result = frames_[k].T_ref_c;
  }
}

void Bootstrap::alignFromStarts(const FrameTracker& tracker, std::size_t k, const std::vector<SE3>& starts) {
  // All starts at once (as in alignToReference), then the same choice as one after the other.
  const std::size_t n = starts.size();
  std::vector<SE3> T_track = starts;
  std::vector<double> alpha(n, std::exp(frames_[k].a)), beta(n, frames_[k].b);
  std::vector<FrameTrackResult> tr(n);
  const auto run = [&](std::size_t c) { tr[c] = tracker.track(images_[k], T_track[c], alpha[c], beta[c]); };
  std::vector<std::future<void>> others;
  for (std::size_t c = 1; c < n; ++c) others.push_back(std::async(std::launch::async, run, c));
  run(0);
  for (std::future<void>& f : others) f.get();
  BootstrapFrame best{frames_[k].t, starts[0].inverse(), frames_[k].a, frames_[k].b};
  double best_rmse = 1e9;
  int won = -1;
  for (std::size_t c = 0; c < n; ++c) {
    if (tr[c].ok && alpha[c] > 0 && tr[c].rmse < best_rmse) {
      best_rmse = tr[c].rmse, won = static_cast<int>(c);
      best = {frames_[k].t, T_track[c].inverse(), std::log(alpha[c]), beta[c]};
    }
  }
  frames_[k] = best;
  if (logEnabled(LogLevel::kDebug))
    logf(LogLevel::kDebug, "bootstrap: frame %zu aligned to the map: %s, rmse %.4f", k,
         won < 0    ? "failed from every start"
         : won == 0 ? "from the motion"
         : won == 1 ? "from the geodesic"
                    : "from the corner tracks",
         best_rmse);
}

void Bootstrap::refineWithViews(const cv::Mat& last_image) {
  const std::size_t n = frames_.size();
  const int views = std::min<int>(cfg_.final_views - 1, static_cast<int>(n) - 1);  // besides the reference
  if (views < 2) return;
  std::vector<std::size_t> pick;
  for (int j = 1; j <= views; ++j)
    pick.push_back(static_cast<std::size_t>(std::lround(j * (n - 1.0) / views)));
  std::vector<BaFrame> fr(1 + pick.size());
  fr[0].image = ref_.image;
  fr[0].fixed = true;
  for (std::size_t j = 0; j < pick.size(); ++j) {
    const BootstrapFrame& f = frames_[pick[j]];
    fr[j + 1].image = pick[j] < images_.size() ? images_[pick[j]] : last_image;
    fr[j + 1].T_w_c = f.T_ref_c, fr[j + 1].a = f.a, fr[j + 1].b = f.b;
  }
  std::vector<BaPoint> pts;
  std::vector<std::size_t> which;
  for (std::size_t i = 0; i < ref_.points.size(); ++i) {
    if (!(ref_.points[i].inv_depth > 0)) continue;
    BaPoint bp;
    bp.host = 0, bp.u = ref_.points[i].u, bp.v = ref_.points[i].v;
    bp.inv_depth = ref_.points[i].inv_depth;
    for (std::size_t j = 1; j < fr.size(); ++j) bp.targets.push_back(static_cast<int>(j));
    pts.push_back(std::move(bp));
    which.push_back(i);
  }
  BaConfig bc = cfg_.ba;
  bc.iterations = 2 * cfg_.ba.iterations;
  const BaStats st = PhotometricBA(cam_, bc).optimize(fr, pts);
  int inliers = 0;
  for (const BaPoint& p : pts) inliers += !p.outlier;
  if (logEnabled(LogLevel::kDebug))
    logf(LogLevel::kDebug, "bootstrap: %d views, %d of %zu points kept, rmse %.4f -> %.4f", views + 1,
         inliers, pts.size(), st.initial_rmse, st.final_rmse);
  if (inliers < cfg_.min_points || st.final_rmse > cfg_.max_rmse) return;
  for (std::size_t j = 0; j < pts.size(); ++j)
    ref_.points[which[j]].inv_depth = pts[j].outlier ? 0.0 : pts[j].inv_depth;
  for (std::size_t j = 0; j < pick.size(); ++j)
    frames_[pick[j]] = {frames_[pick[j]].t, fr[j + 1].T_w_c, fr[j + 1].a, fr[j + 1].b};
  parallax_ = translationParallax(frames_.back().T_ref_c.inverse());
  realignFrames(frames_.back().t, frames_.back().T_ref_c, 1.0, n - 1);
}

bool Bootstrap::initFromGeometry(TimeNs t, const cv::Mat& image, const GeometricInitResult& g) {
  // Depths of the reference's points from the nearest triangulated corners.
  std::vector<cv::Point> px;
  for (const KeyframePoint& p : ref_.points) px.emplace_back(static_cast<int>(p.u), static_cast<int>(p.v));
  const std::vector<double> rho = fillInverseDepth(px, g.points, cfg_.fill);
  Keyframe ref = ref_;
  for (std::size_t i = 0; i < ref.points.size(); ++i) ref.points[i].inv_depth = rho[i];
  // Two-frame photometric refinement from the geometric pose, no depth prior.
  std::vector<BaFrame> fr(2);
  fr[0].image = ref.image;
  fr[0].fixed = true;
  fr[1].image = image;
  fr[1].T_w_c = g.T_c_ref.inverse();
  fr[1].a = frames_.back().a, fr[1].b = frames_.back().b;
  std::vector<BaPoint> pts;
  std::vector<std::size_t> which;
  for (std::size_t i = 0; i < ref.points.size(); ++i) {
    if (!(rho[i] > 0)) continue;
    BaPoint bp;
    bp.host = 0, bp.u = ref.points[i].u, bp.v = ref.points[i].v;
    bp.inv_depth = rho[i];
    bp.targets = {1};
    pts.push_back(bp);
    which.push_back(i);
  }
  if (static_cast<int>(pts.size()) < cfg_.min_points) return false;
  BaConfig bc = cfg_.ba;
  bc.iterations = 2 * cfg_.ba.iterations;
  const BaStats st = PhotometricBA(cam_, bc).optimize(fr, pts);
  if (logEnabled(LogLevel::kDebug))
    logf(LogLevel::kDebug,
         "bootstrap: geometric init, %d inliers, %zu triangulated, %zu points, rmse %.4f -> %.4f", g.inliers,
         g.points.size(), pts.size(), st.initial_rmse, st.final_rmse);
  if (st.final_rmse > cfg_.max_rmse) return false;
  for (KeyframePoint& p : ref.points) p.inv_depth = 0;
  int inliers = 0;
  for (std::size_t j = 0; j < pts.size(); ++j)
    if (!pts[j].outlier) ref.points[which[j]].inv_depth = pts[j].inv_depth, ++inliers;
  if (inliers < cfg_.min_points) return false;
  ref_ = std::move(ref);
  rmse_ = st.final_rmse;
  // The frames in between: aligned to the new map, the photometric path's relative motion rescaled to
  // the geometric translation.
  const SE3 T_ref_last = fr[1].T_w_c;
  const double photo_len = frames_.back().T_ref_c.translation().norm();
  // The corner tracks' poses are in the triangulation's scale, which the adjustment changed.
  std::vector<std::optional<SE3>> T_ref_c_tracks;
  if (g.T_c_ref_before.size() + 1 == frames_.size())
    for (const std::optional<SE3>& T : g.T_c_ref_before) {
      T_ref_c_tracks.push_back(T ? std::optional<SE3>(T->inverse()) : std::nullopt);
      if (T)
        T_ref_c_tracks.back()->translation() *=
            T_ref_last.translation().norm() / g.T_c_ref.translation().norm();
    }
  realignFrames(t, T_ref_last, photo_len > 1e-9 ? T_ref_last.translation().norm() / photo_len : 1.0,
                frames_.size(), T_ref_c_tracks);
  frames_.push_back({t, T_ref_last, fr[1].a, fr[1].b});
  parallax_ = translationParallax(T_ref_last.inverse());
  refineWithViews(image);
  geometric_used_ = true;
  normalizeScale();
  done_ = true;
  return true;
}

}  // namespace eds
