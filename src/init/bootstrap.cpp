#include "init/bootstrap.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace eds {

void BootstrapConfig::validate() const {
  points.validate();
  if (!(min_parallax_px > 0) || min_points < 1 || min_frames < 1 || max_frames <= min_frames ||
      !(max_rmse > 0) || depth_prior_weight < 0)
    throw std::invalid_argument("bootstrap: bad configuration");
}

Bootstrap::Bootstrap(const CameraModel& pinhole, BootstrapConfig cfg)
    : cam_(pinhole), cfg_(cfg) {
  cfg_.validate();
}

bool Bootstrap::setReference(TimeNs t, const cv::Mat& image) {
  Keyframe kf;
  kf.t = t;
  setKeyframeImage(kf, image);
  const std::vector<cv::Point> pts = selectPoints(kf.grad_x, kf.grad_y, cfg_.points);
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
  if (static_cast<int>(kf.points.size()) < cfg_.min_points) {
    has_ref_ = false;
    return false;
  }
  ref_ = std::move(kf);
  has_ref_ = true;
  frames_.push_back({t, SE3(), 0.0, 0.0});
  return true;
}

double Bootstrap::translationParallax(const SE3& T_c_ref) const {
  const Mat3 R = T_c_ref.rotationMatrix();
  const Vec3 t = T_c_ref.translation();
  double ss = 0;
  int n = 0;
  for (const KeyframePoint& p : ref_.points) {
    if (!(p.inv_depth > 0)) continue;
    const Vec3 x((p.u - cam_.cx) / cam_.fx, (p.v - cam_.cy) / cam_.fy, 1.0);
    const Vec3 q0 = R * x, q1 = q0 + t * p.inv_depth;  // same ray, scaled by ρ: no division by ρ
    if (q0.z() <= 1e-9 || q1.z() <= 1e-9) continue;
    const double du = cam_.fx * (q1.x() / q1.z() - q0.x() / q0.z());
    const double dv = cam_.fy * (q1.y() / q1.z() - q0.y() / q0.z());
    ss += du * du + dv * dv;
    ++n;
  }
  return n ? std::sqrt(ss / n) : 0.0;
}

bool Bootstrap::add(TimeNs t, const cv::Mat& image) {
  if (done_) throw std::logic_error("Bootstrap::add after initialization");
  last_image_ = image;
  if (!has_ref_) {
    setReference(t, image);
    return false;
  }
  // Constant-velocity prediction in the reference frame.
  SE3 T_c_ref = frames_.back().T_ref_c.inverse();
  if (frames_.size() >= 2) {
    const SE3 T_last = frames_.back().T_ref_c.inverse(),
              T_prev = frames_[frames_.size() - 2].T_ref_c.inverse();
    T_c_ref = (T_last * T_prev.inverse()) * T_last;
  }
  double alpha = std::exp(frames_.back().a), beta = frames_.back().b;

  FrameTracker tracker(cam_, cfg_.tracker);
  tracker.setKeyframe(ref_);
  const FrameTrackResult tr = tracker.track(image, T_c_ref, alpha, beta);
  if (!tr.ok || !(alpha > 0)) {
    // The prediction may have been the problem: retry from the last pose before giving up.
    T_c_ref = frames_.back().T_ref_c.inverse();
    alpha = std::exp(frames_.back().a), beta = frames_.back().b;
    if (!tracker.track(image, T_c_ref, alpha, beta).ok || !(alpha > 0)) {
      ++restarts_;
      setReference(t, image);
      return false;
    }
  }

  // Two-frame photometric BA, pose and inverse depths together, coarse-to-fine: the same points on
  // every pyramid level (their pattern spans more of the scene on coarse levels), so that depths far
  // from the constant start (large motion between the first frames) come into the basin.
  std::vector<cv::Mat> ref_pyr, cur_pyr;
  tracker.pyramid(ref_.image, ref_pyr);
  tracker.pyramid(image, cur_pyr);
  std::vector<BaFrame> fr(2);
  fr[0].fixed = true;
  fr[1].T_w_c = T_c_ref.inverse();
  fr[1].a = std::log(alpha), fr[1].b = beta;
  std::vector<BaPoint> pts;
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
    CameraModel c = cam_;
    c.fx *= s, c.fy *= s;
    c.cx = (cam_.cx + 0.5) * s - 0.5, c.cy = (cam_.cy + 0.5) * s - 0.5;
    c.width = ref_pyr[l].cols, c.height = ref_pyr[l].rows;
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

  rmse_ = st.final_rmse;
  // Points that do not match (occluded, out of view) keep their depth but are marked unknown.
  int inliers = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ref_.points[i].inv_depth = pts[i].outlier ? 0.0 : pts[i].inv_depth;
    inliers += !pts[i].outlier;
  }
  T_c_ref = fr[1].T_w_c.inverse();
  frames_.push_back({t, fr[1].T_w_c, fr[1].a, fr[1].b});
  parallax_ = translationParallax(T_c_ref);

  const int n_after = static_cast<int>(frames_.size()) - 1;
  if (std::getenv("EDS_DEBUG"))
    std::fprintf(stderr, "bootstrap: frame %d parallax %.2f px rmse %.4f inliers %d/%zu t %.3f %.3f %.3f\n", n_after,
                 parallax_, rmse_, inliers, pts.size(), fr[1].T_w_c.translation().x(), fr[1].T_w_c.translation().y(),
                 fr[1].T_w_c.translation().z());
  if (rmse_ > cfg_.max_rmse || inliers < cfg_.min_points || n_after > cfg_.max_frames) {
    ++restarts_;
    setReference(t, image);
    return false;
  }
  if (n_after < cfg_.min_frames || parallax_ < cfg_.min_parallax_px) return false;

  // Success: mean inverse depth 1, translations scaled to match (depths × m, so translations × m).
  double sum = 0;
  int n = 0;
  for (const KeyframePoint& p : ref_.points)
    if (p.inv_depth > 0) sum += p.inv_depth, ++n;
  const double m = sum / n;
  for (KeyframePoint& p : ref_.points) p.inv_depth /= m;
  for (BootstrapFrame& f : frames_) f.T_ref_c.translation() *= m;
  done_ = true;
  return true;
}

}  // namespace eds
