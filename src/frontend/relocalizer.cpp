#include "frontend/relocalizer.hpp"

#include <algorithm>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/ocl.hpp>
#include <opencv2/features2d.hpp>

namespace eds {

namespace {

cv::Mat as8bit(const cv::Mat& img) {
  if (img.type() == CV_8UC1) return img;
  cv::Mat out;
  img.convertTo(out, CV_8U, 255.0);
  return out;
}

// The inverse depth at a pixel: that of the nearest keyframe point within `radius` px (0: none). The
// points lie on a grid of buckets, so a lookup reads a few of them.
class DepthLookup {
 public:
  DepthLookup(const std::vector<KeyframePoint>& pts, int width, int height, int radius)
      : cell_(radius), cols_(width / radius + 1), rows_(height / radius + 1), buckets_(cols_ * rows_) {
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (pts[i].inv_depth > 0) buckets_[bucket(pts[i].u, pts[i].v)].push_back(&pts[i]);
  }
  double at(float u, float v) const {
    const int bx = static_cast<int>(u) / cell_, by = static_cast<int>(v) / cell_;
    double best_d2 = static_cast<double>(cell_) * cell_, inv = 0;
    for (int y = std::max(by - 1, 0); y <= std::min(by + 1, rows_ - 1); ++y)
      for (int x = std::max(bx - 1, 0); x <= std::min(bx + 1, cols_ - 1); ++x)
        for (const KeyframePoint* p : buckets_[static_cast<std::size_t>(y * cols_ + x)]) {
          const double d2 = (p->u - u) * (p->u - u) + (p->v - v) * (p->v - v);
          if (d2 < best_d2) best_d2 = d2, inv = p->inv_depth;
        }
    return inv;
  }

 private:
  std::size_t bucket(float u, float v) const {
    const int x = std::clamp(static_cast<int>(u) / cell_, 0, cols_ - 1);
    const int y = std::clamp(static_cast<int>(v) / cell_, 0, rows_ - 1);
    return static_cast<std::size_t>(y * cols_ + x);
  }
  int cell_, cols_, rows_;
  std::vector<std::vector<const KeyframePoint*>> buckets_;
};

}  // namespace

FeatureMatches matchFeatures(const cv::Mat& a, const cv::Mat& b, const FeatureMatchConfig& cfg) {
  // OpenCV's OpenCL path (a per-thread switch) would load a GPU runtime and compile kernels in the
  // middle of a recovery, and its results may differ from the CPU's; these images are small.
  cv::ocl::setUseOpenCL(false);
  // Corners detected in both images (matched corner to corner, so both sides are located alike).
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(cfg.features);
  std::vector<cv::KeyPoint> a_keys, b_keys;
  cv::Mat a_desc, b_desc;
  orb->detectAndCompute(as8bit(a), cv::noArray(), a_keys, a_desc);
  orb->detectAndCompute(as8bit(b), cv::noArray(), b_keys, b_desc);
  FeatureMatches out;
  if (a_desc.empty() || b_desc.empty()) return out;
  std::vector<std::vector<cv::DMatch>> knn;
  cv::BFMatcher(cv::NORM_HAMMING).knnMatch(b_desc, a_desc, knn, 2);
  for (const auto& m : knn) {
    if (m.empty() || m[0].distance > cfg.max_hamming) continue;
    if (m.size() > 1 && m[0].distance > cfg.ratio * m[1].distance) continue;
    out.a.push_back(a_keys[static_cast<std::size_t>(m[0].trainIdx)].pt);
    out.b.push_back(b_keys[static_cast<std::size_t>(m[0].queryIdx)].pt);
  }
  return out;
}

Relocalization relocalize(const Keyframe& kf, const cv::Mat& frame, const CameraModel& pinhole,
                          const RelocalizerConfig& cfg) {
  Relocalization out;
  // A keyframe corner takes the depth of the keyframe point nearest to it.
  const FeatureMatches m = matchFeatures(kf.image, frame, {cfg.features, cfg.max_hamming, cfg.ratio});
  const DepthLookup depth(kf.points, kf.image.cols, kf.image.rows, cfg.depth_radius_px);
  std::vector<cv::Point3f> p_kf;
  std::vector<cv::Point2f> px_f;
  for (std::size_t i = 0; i < m.a.size(); ++i) {
    const double inv_depth = depth.at(m.a[i].x, m.a[i].y);
    if (!(inv_depth > 0)) continue;
    const Vec3 X = pinhole.pinholeRay(m.a[i].x, m.a[i].y) / inv_depth;
    p_kf.emplace_back(static_cast<float>(X.x()), static_cast<float>(X.y()), static_cast<float>(X.z()));
    px_f.push_back(m.b[i]);
  }
  out.matches = static_cast<int>(p_kf.size());
  if (out.matches < cfg.min_inliers) return out;

  const cv::Matx33d K(pinhole.fx, 0, pinhole.cx, 0, pinhole.fy, pinhole.cy, 0, 0, 1);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  // OpenCV's RANSAC seeds its own generator: the same input gives the same pose.
  if (!cv::solvePnPRansac(p_kf, px_f, K, cv::noArray(), rvec, tvec, false, 200,
                          static_cast<float>(cfg.ransac_px), 0.999, inliers, cv::SOLVEPNP_EPNP))
    return out;
  out.inliers = static_cast<int>(inliers.size());
  if (out.inliers < cfg.min_inliers || out.inliers < cfg.min_inlier_fraction * out.matches) return out;
  // EPnP's closed form is loose on a flat scene; Levenberg-Marquardt on the inliers' reprojection
  // errors polishes it.
  std::vector<cv::Point3f> in_kf;
  std::vector<cv::Point2f> in_f;
  for (int i : inliers)
    in_kf.push_back(p_kf[static_cast<std::size_t>(i)]), in_f.push_back(px_f[static_cast<std::size_t>(i)]);
  cv::solvePnPRefineLM(in_kf, in_f, K, cv::noArray(), rvec, tvec);
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Mat3 R_f_kf;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R_f_kf(r, c) = R.at<double>(r, c);
  out.T_f_kf =
      SE3(Quat(R_f_kf).normalized(), Vec3(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
  out.ok = true;
  return out;
}

}  // namespace eds
