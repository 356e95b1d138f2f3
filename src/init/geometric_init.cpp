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
  const cv::Mat ref8 = toGray8(ref_image);
  cv::buildOpticalFlowPyramid(ref8, prev_pyr_, kWindow, kLevels, true);
  ref_.clear();
  cv::goodFeaturesToTrack(ref8, ref_, cfg_.max_features, cfg_.quality, cfg_.min_distance);
  cur_ = ref_;
  corners_ = ref_.size();
  ids_.resize(ref_.size());
  for (std::size_t i = 0; i < ids_.size(); ++i) ids_[i] = static_cast<int>(i);
  seen_.clear();
}

std::optional<GeometricInitResult> GeometricInit::add(const cv::Mat& image, bool sparse) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  seen_.emplace_back(corners_, cv::Point2f(nan, nan));
  if (prev_pyr_.empty() || static_cast<int>(cur_.size()) < cfg_.min_tracks) return std::nullopt;
  const cv::Mat gray = toGray8(image);
  std::vector<cv::Point2f> next, back;
  std::vector<unsigned char> st, st_back;
  std::vector<float> err;
  const cv::Size win = kWindow;
  // Each image's pyramid (with its derivatives) built once: it serves both directions of this frame's
  // check and the next frame's tracking.
  std::vector<cv::Mat> pyr;
  cv::buildOpticalFlowPyramid(gray, pyr, win, kLevels, true);
  cv::calcOpticalFlowPyrLK(prev_pyr_, pyr, cur_, next, st, err, win, kLevels);
  cv::calcOpticalFlowPyrLK(pyr, prev_pyr_, next, back, st_back, err, win, kLevels);
  const std::size_t n_before = cur_.size();
  std::size_t k = 0;
  for (std::size_t i = 0; i < cur_.size(); ++i) {
    const bool inside =
        next[i].x >= 0 && next[i].y >= 0 && next[i].x <= gray.cols - 1 && next[i].y <= gray.rows - 1;
    if (!st[i] || !st_back[i] || !inside || cv::norm(back[i] - cur_[i]) > 0.5) continue;
    ref_[k] = ref_[i];
    cur_[k] = next[i];
    ids_[k] = ids_[i];
    seen_.back()[ids_[k]] = next[i];
    ++k;
  }
  ref_.resize(k);
  cur_.resize(k);
  ids_.resize(k);
  prev_pyr_ = std::move(pyr);
  if (static_cast<int>(k) < cfg_.min_tracks) return std::nullopt;
  std::vector<double> flow(k);
  for (std::size_t i = 0; i < k; ++i) flow[i] = cv::norm(cur_[i] - ref_[i]);
  std::nth_element(flow.begin(), flow.begin() + k / 2, flow.end());
  if (logEnabled(LogLevel::kDebug))
    logf(LogLevel::kDebug, "bootstrap: %zu of %zu corners tracked, median flow %.1f px", k, n_before,
         flow[k / 2]);
  if (flow[k / 2] < cfg_.min_flow_px) return std::nullopt;

  const cv::Matx33d K(cam_.fx, 0, cam_.cx, 0, cam_.fy, cam_.cy, 0, 0, 1);
  cv::Mat mask_e, mask_h;
  cv::Mat E = cv::findEssentialMat(ref_, cur_, K, cv::RANSAC, 0.999, cfg_.ransac_px, mask_e);
  const cv::Mat Hm = cv::findHomography(ref_, cur_, cv::RANSAC, cfg_.ransac_px, mask_h);
  GeometricInitResult res;
  if (E.rows != 3 || E.cols != 3) {  // several solutions or none: not this frame
    logf(LogLevel::kDebug, "bootstrap: no single essential matrix");
    return std::nullopt;
  }
  const int n_e = cv::countNonZero(mask_e), n_h = Hm.empty() ? 0 : cv::countNonZero(mask_h);
  res.planar = n_h >= cfg_.planar_ratio * n_e;
  if (res.planar) return res;
  cv::Mat R, t;
  res.inliers = cv::recoverPose(E, ref_, cur_, K, R, t, mask_e);
  if (res.inliers < cfg_.min_tracks) {
    // Most of RANSAC's inliers behind a camera: with a dominant far plane many essential matrices fit
    // the tracks about as well, and RANSAC's first consensus can be one of the wrong ones. MAGSAC++
    // scores every hypothesis by all residuals and refines it, which separates them.
    logf(LogLevel::kDebug, "bootstrap: %d essential-matrix inliers (RANSAC %d, homography %d)", res.inliers,
         n_e, n_h);
    E = cv::findEssentialMat(ref_, cur_, K, cv::USAC_MAGSAC, 0.999, cfg_.ransac_px, mask_e);
    if (E.rows != 3 || E.cols != 3) return std::nullopt;
    res.inliers = cv::recoverPose(E, ref_, cur_, K, R, t, mask_e);
    logf(LogLevel::kDebug, "bootstrap: %d essential-matrix inliers by MAGSAC++", res.inliers);
    if (res.inliers < cfg_.min_tracks) return std::nullopt;
  }
  Mat3 Re;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Re(r, c) = R.at<double>(r, c);
  const Vec3 te(t.at<double>(0), t.at<double>(1), t.at<double>(2));
  res.T_c_ref = SE3(Quat(Re).normalized(), te);
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
  logf(LogLevel::kDebug, "bootstrap: %d essential-matrix inliers (homography %d), %zu triangulated",
       res.inliers, n_h, res.points.size());
  if (static_cast<int>(res.points.size()) < cfg_.min_tracks) return std::nullopt;
  std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
  res.parallax_deg = angles[angles.size() / 2] * 180.0 / M_PI;
  if (res.parallax_deg < (sparse ? cfg_.min_parallax_deg_sparse : cfg_.min_parallax_deg)) {
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
