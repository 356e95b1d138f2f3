#include "init/geometric_init.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "core/log.hpp"

namespace eds {

namespace {
cv::Mat toGray8(const cv::Mat& img) {
  cv::Mat g;
  img.convertTo(g, CV_8U, img.type() == CV_32F ? 255.0 : 1.0);
  return g;
}
}  // namespace

GeometricInit::GeometricInit(const CameraModel& pinhole, GeometricInitConfig cfg)
    : cam_(pinhole), cfg_(cfg) {}

void GeometricInit::reset(const cv::Mat& ref_image) {
  ref8_ = toGray8(ref_image);
  cv::buildOpticalFlowPyramid(ref8_, ref_pyr_, kWindow, kLevels, true);
  prev_pyr_ = ref_pyr_;
  ref_.clear();
  cv::goodFeaturesToTrack(ref8_, ref_, cfg_.max_features, cfg_.quality, cfg_.min_distance);
  cur_ = ref_;
  corners0_ = ref_;
  corners_ = ref_.size();
  ids_.resize(ref_.size());
  for (std::size_t i = 0; i < ids_.size(); ++i) ids_[i] = static_cast<int>(i);
  seen_.clear();
  from_events_ = from_features_ = raw_matches_ = false;
}

// Tracks `from` (points of `from_pyr`) into `pyr` (forward and back), from `predicted` where given;
// keep[i] says whether track i passed the check. Returns how many did.
std::size_t GeometricInit::track(const std::vector<cv::Mat>& from_pyr, const std::vector<cv::Point2f>& from,
                                 const std::vector<cv::Mat>& pyr, cv::Size size,
                                 const std::vector<cv::Point2f>* predicted, std::vector<cv::Point2f>& next,
                                 std::vector<unsigned char>& keep) const {
  std::vector<cv::Point2f> back;
  std::vector<unsigned char> st, st_back;
  std::vector<float> err;
  int flags = 0;
  // From a prediction the check tracks back from the corners' previous positions as well: from where
  // the forward tracking ended it would not reach them either.
  if (predicted) next = *predicted, back = from, flags = cv::OPTFLOW_USE_INITIAL_FLOW;
  const cv::TermCriteria term(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
  cv::calcOpticalFlowPyrLK(from_pyr, pyr, from, next, st, err, kWindow, kLevels, term, flags);
  cv::calcOpticalFlowPyrLK(pyr, from_pyr, next, back, st_back, err, kWindow, kLevels, term, flags);
  keep.assign(from.size(), 0);
  std::size_t k = 0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const bool inside =
        next[i].x >= 0 && next[i].y >= 0 && next[i].x <= size.width - 1 && next[i].y <= size.height - 1;
    keep[i] = st[i] && st_back[i] && inside && cv::norm(back[i] - from[i]) <= 0.5;
    k += keep[i];
  }
  return k;
}

// Where the corners are under the pose T_c_ref with the reference at unit depth (the scale the events'
// pose comes in during the bootstrap).
std::vector<cv::Point2f> GeometricInit::predict(const SE3& T_c_ref) const {
  std::vector<cv::Point2f> pred(cur_.size());
  for (std::size_t i = 0; i < cur_.size(); ++i) {
    const Vec3 q = T_c_ref * cam_.pinholeRay(ref_[i].x, ref_[i].y);
    pred[i] = q.z() > 1e-6 ? cv::Point2f(static_cast<float>(cam_.fx * q.x() / q.z() + cam_.cx),
                                         static_cast<float>(cam_.fy * q.y() / q.z() + cam_.cy))
                           : cur_[i];
  }
  return pred;
}

// Tracks the corners into the next image and drops the lost ones; true when enough are left and they
// moved far enough for a two-view estimate.
bool GeometricInit::advance(const cv::Mat& image, bool sparse, const SE3* hint, double interval_s) {
  const cv::Mat gray = toGray8(image);
  // Each image's pyramid (with its derivatives) built once: it serves both directions of this frame's
  // check and the next frame's tracking.
  std::vector<cv::Mat> pyr;
  cv::buildOpticalFlowPyramid(gray, pyr, kWindow, kLevels, true);
  std::vector<cv::Point2f> next;
  std::vector<unsigned char> keep;
  std::size_t k = track(prev_pyr_, cur_, pyr, gray.size(), nullptr, next, keep);
  if (cfg_.from_events && hint && sparse && static_cast<int>(k) < cfg_.min_tracks) {
    // Between frames far apart the corners move beyond the window's reach: start them where the events'
    // pose puts them.
    std::vector<cv::Point2f> next_h;
    std::vector<unsigned char> keep_h;
    const std::vector<cv::Point2f> predicted = predict(*hint);
    const std::size_t k_h = track(prev_pyr_, cur_, pyr, gray.size(), &predicted, next_h, keep_h);
    logf(LogLevel::kDebug, "bootstrap: %zu corners tracked, %zu from the events' pose", k, k_h);
    if (k_h > k) next.swap(next_h), keep.swap(keep_h), from_events_ = true;
  }
  const std::size_t n_before = cur_.size();
  k = 0;
  for (std::size_t i = 0; i < n_before; ++i) {
    if (!keep[i]) continue;
    ref_[k] = ref_[i];
    cur_[k] = next[i];
    ids_[k] = ids_[i];
    seen_.back()[ids_[k]] = next[i];
    ++k;
  }
  ref_.resize(k);
  cur_.resize(k);
  ids_.resize(k);
  if (cfg_.from_features && sparse && interval_s >= cfg_.features_min_interval_s &&
      static_cast<int>(k) < cfg_.min_tracks) {
    matchFeaturesInstead(gray, pyr);
    k = cur_.size();
  }
  prev_pyr_ = std::move(pyr);
  if (static_cast<int>(k) < cfg_.min_tracks) return false;
  std::vector<double> flow(k);
  for (std::size_t i = 0; i < k; ++i) flow[i] = cv::norm(cur_[i] - ref_[i]);
  std::nth_element(flow.begin(), flow.begin() + k / 2, flow.end());
  if (logEnabled(LogLevel::kDebug))
    logf(LogLevel::kDebug, "bootstrap: %zu of %zu corners tracked, median flow %.1f px", k, n_before,
         flow[k / 2]);
  return flow[k / 2] >= cfg_.min_flow_px;
}

// Where the matched features move the reference's corners: each by the median displacement of the
// matches nearest to it in the reference (the scene's depth varies; neighbours mostly share it).
std::vector<cv::Point2f> GeometricInit::flowFromMatches(const FeatureMatches& m) const {
  constexpr std::size_t kNearest = 5;
  std::vector<cv::Point2f> pred(corners0_.size());
  std::vector<std::pair<float, std::size_t>> by_distance(m.a.size());
  std::vector<float> dx(kNearest), dy(kNearest);
  for (std::size_t i = 0; i < corners0_.size(); ++i) {
    for (std::size_t j = 0; j < m.a.size(); ++j) {
      const cv::Point2f d = m.a[j] - corners0_[i];
      by_distance[j] = {d.dot(d), j};
    }
    const std::size_t n = std::min(kNearest, by_distance.size());
    std::partial_sort(by_distance.begin(), by_distance.begin() + n, by_distance.end());
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t q = by_distance[j].second;
      dx[j] = m.b[q].x - m.a[q].x, dy[j] = m.b[q].y - m.a[q].y;
    }
    std::nth_element(dx.begin(), dx.begin() + n / 2, dx.begin() + n);
    std::nth_element(dy.begin(), dy.begin() + n / 2, dy.begin() + n);
    pred[i] = corners0_[i] + cv::Point2f(dx[n / 2], dy[n / 2]);
  }
  return pred;
}

// The reference's corners tracked again into the frame (`gray`, its pyramid `pyr`) from where the
// reference's matched ORB features put them; they replace the tracks where they are more (new track
// ids, unseen in the frames before).
void GeometricInit::matchFeaturesInstead(const cv::Mat& gray, const std::vector<cv::Mat>& pyr) {
  const FeatureMatches m = matchFeatures(ref8_, gray, cfg_.features);
  if (m.a.size() < 5) return;
  const std::vector<cv::Point2f> predicted = flowFromMatches(m);
  std::vector<cv::Point2f> next;
  std::vector<unsigned char> keep;
  const std::size_t k = track(ref_pyr_, corners0_, pyr, gray.size(), &predicted, next, keep);
  logf(LogLevel::kDebug, "bootstrap: %zu corners tracked, %zu features matched, %zu corners from them",
       cur_.size(), m.a.size(), k);
  // Too few of them (a wide swing distorts the corners' windows, near objects occlude): the matches
  // themselves, whole pixels of ORB's levels as they are (their essential matrix is rougher).
  const bool raw = static_cast<int>(k) < cfg_.min_tracks && m.a.size() > k;
  if (std::max(k, raw ? m.a.size() : 0) <= cur_.size()) return;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  ref_.clear(), cur_.clear(), ids_.clear();
  for (std::size_t i = 0; i < (raw ? m.a.size() : corners0_.size()); ++i) {
    if (!raw && !keep[i]) continue;
    ref_.push_back(raw ? m.a[i] : corners0_[i]), cur_.push_back(raw ? m.b[i] : next[i]);
  }
  for (std::vector<cv::Point2f>& s : seen_) s.resize(corners_ + cur_.size(), cv::Point2f(nan, nan));
  for (std::size_t i = 0; i < cur_.size(); ++i) {
    ids_.push_back(static_cast<int>(corners_ + i));
    seen_.back()[corners_ + i] = cur_[i];
  }
  corners_ += cur_.size();
  from_events_ = false, from_features_ = true, raw_matches_ = raw;
}

// The two-view motion of the live tracks: the planar verdict, or the essential matrix's pose with its
// inliers in mask_e (and its rotation and translation as recovered, Re and te). False when neither holds.
// `hint`: the events' pose, given when the tracks were started from it.
bool GeometricInit::twoViewMotion(GeometricInitResult& res, const SE3* hint, cv::Mat& mask_e, Mat3& Re,
                                  Vec3& te) const {
  const cv::Matx33d K(cam_.fx, 0, cam_.cx, 0, cam_.fy, cam_.cy, 0, 0, 1);
  cv::Mat mask_h;
  cv::Mat E = cv::findEssentialMat(ref_, cur_, K, cv::RANSAC, 0.999, cfg_.ransac_px, mask_e);
  const cv::Mat Hm = cv::findHomography(ref_, cur_, cv::RANSAC, cfg_.ransac_px, mask_h);
  if (E.rows != 3 || E.cols != 3) {  // several solutions or none: not this frame
    logf(LogLevel::kDebug, "bootstrap: no single essential matrix");
    return false;
  }
  const int n_e = cv::countNonZero(mask_e), n_h = Hm.empty() ? 0 : cv::countNonZero(mask_h);
  res.planar = n_h >= cfg_.planar_ratio * n_e;
  if (res.planar) return true;
  cv::Mat R, t;
  res.inliers = cv::recoverPose(E, ref_, cur_, K, R, t, mask_e);
  const bool retry = res.inliers < cfg_.min_tracks;
  if (retry) {
    // Most of RANSAC's inliers behind a camera: with a dominant far plane many essential matrices fit
    // the tracks about as well, and RANSAC's first consensus can be one of the wrong ones. MAGSAC++
    // scores every hypothesis by all residuals and refines it, which separates them.
    logf(LogLevel::kDebug, "bootstrap: %d essential-matrix inliers (RANSAC %d, homography %d)", res.inliers,
         n_e, n_h);
    E = cv::findEssentialMat(ref_, cur_, K, cv::USAC_MAGSAC, 0.999, cfg_.ransac_px, mask_e);
    if (E.rows != 3 || E.cols != 3) return false;
    res.inliers = cv::recoverPose(E, ref_, cur_, K, R, t, mask_e);
    logf(LogLevel::kDebug, "bootstrap: %d essential-matrix inliers by MAGSAC++", res.inliers);
    if (res.inliers < cfg_.min_tracks) return false;
  }
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Re(r, c) = R.at<double>(r, c);
  te = Vec3(t.at<double>(0), t.at<double>(1), t.at<double>(2));
  res.T_c_ref = SE3(Quat(Re).normalized(), te);
  if (retry && hint) {
    const double cos_dir = hint->translation().normalized().dot(te.normalized());
    const double dir_deg = std::acos(std::clamp(cos_dir, -1.0, 1.0)) * 180 / M_PI;
    logf(LogLevel::kDebug, "bootstrap: MAGSAC++'s translation %.1f deg from the events'", dir_deg);
    if (!(dir_deg <= cfg_.max_events_direction_deg)) return false;
  }
  logf(LogLevel::kDebug, "bootstrap: %d essential-matrix inliers (homography %d)", res.inliers, n_h);
  return true;
}

std::optional<GeometricInitResult> GeometricInit::add(const cv::Mat& image, bool sparse, const SE3* hint,
                                                      double interval_s) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  seen_.emplace_back(corners_, cv::Point2f(nan, nan));
  from_events_ = from_features_ = raw_matches_ = false;
  if (prev_pyr_.empty() || static_cast<int>(cur_.size()) < cfg_.min_tracks) return std::nullopt;
  if (!advance(image, sparse, hint, interval_s)) return std::nullopt;
  GeometricInitResult res;
  cv::Mat mask_e;
  Mat3 Re;
  Vec3 te;
  if (!twoViewMotion(res, tracksReseeded() ? hint : nullptr, mask_e, Re, te)) return std::nullopt;
  if (res.planar) return res;
  const std::size_t k = cur_.size();
  std::vector<double> angles;
  std::vector<int> triangulated;
  std::vector<Vec3> X_ref;
  // Triangulation by the midpoint-free linear method on normalized coordinates (depth in the reference).
  for (std::size_t i = 0; i < k; ++i) {
    if (!mask_e.at<unsigned char>(static_cast<int>(i))) continue;
    const Vec3 x0 = cam_.pinholeRay(ref_[i].x, ref_[i].y);
    const Vec3 x1 = cam_.pinholeRay(cur_[i].x, cur_[i].y);
    // z·(R x0) + t = s·x1: least squares for (z, s).
    Eigen::Matrix<double, 3, 2> A;
    A.col(0) = Re * x0;
    A.col(1) = -x1;
    const Eigen::Vector2d zs = A.colPivHouseholderQr().solve(-te);
    if (!(zs[0] > 1e-6) || !(zs[1] > 1e-6)) continue;
    const Vec3 X1 = Re * (x0 * zs[0]) + te;
    const double du = cam_.fx * X1.x() / X1.z() + cam_.cx - cur_[i].x;
    const double dv = cam_.fy * X1.y() / X1.z() + cam_.cy - cur_[i].y;
    if (du * du + dv * dv > cfg_.max_reproj_px * cfg_.max_reproj_px) continue;
    res.points.push_back({ref_[i].x, ref_[i].y, 1.0 / zs[0]});
    triangulated.push_back(ids_[i]);
    X_ref.push_back(x0 * zs[0]);
    // Angle between the ray from the reference and the ray from the current camera, at the point.
    const Vec3 X0 = x0 * zs[0], c1 = -(Re.transpose() * te);
    angles.push_back(std::acos(std::clamp(X0.normalized().dot((X0 - c1).normalized()), -1.0, 1.0)));
  }
  logf(LogLevel::kDebug, "bootstrap: %zu of %d inliers triangulated", res.points.size(), res.inliers);
  if (static_cast<int>(res.points.size()) < cfg_.min_tracks) return std::nullopt;
  std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
  res.parallax_deg = angles[angles.size() / 2] * 180.0 / M_PI;
  const double min_parallax = raw_matches_ ? cfg_.min_parallax_deg_matches
                              : sparse     ? cfg_.min_parallax_deg_sparse
                                           : cfg_.min_parallax_deg;
  if (res.parallax_deg < min_parallax) {
    logf(LogLevel::kDebug, "bootstrap: median triangulation angle %.2f deg", res.parallax_deg);
    return std::nullopt;
  }
  res.T_c_ref_before = posesBefore(triangulated, X_ref);
  return res;
}

std::vector<std::optional<SE3>> GeometricInit::posesBefore(const std::vector<int>& triangulated,
                                                           const std::vector<Vec3>& X_ref) const {
  const cv::Matx33d K(cam_.fx, 0, cam_.cx, 0, cam_.fy, cam_.cy, 0, 0, 1);
  std::vector<std::optional<SE3>> poses;
  std::vector<cv::Point3f> obj;
  std::vector<cv::Point2f> img;
  for (std::size_t j = 0; j + 1 < seen_.size(); ++j) {
    obj.clear(), img.clear();
    for (std::size_t n = 0; n < triangulated.size(); ++n) {
      const cv::Point2f q = seen_[j][triangulated[n]];
      if (std::isnan(q.x)) continue;
      obj.emplace_back(X_ref[n].x(), X_ref[n].y(), X_ref[n].z());
      img.push_back(q);
    }
    cv::Mat rvec, tvec, R;
    std::vector<int> inliers;
    if (static_cast<int>(obj.size()) < cfg_.min_tracks ||
        !cv::solvePnPRansac(obj, img, K, cv::noArray(), rvec, tvec, false, 100,
                            static_cast<float>(cfg_.max_reproj_px), 0.99, inliers, cv::SOLVEPNP_SQPNP) ||
        static_cast<int>(inliers.size()) < cfg_.min_tracks) {
      poses.emplace_back();
      continue;
    }
    cv::Rodrigues(rvec, R);
    Mat3 Rm;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Rm(r, c) = R.at<double>(r, c);
    poses.emplace_back(
        SE3(Quat(Rm).normalized(), Vec3(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2))));
  }
  return poses;
}

}  // namespace eds
