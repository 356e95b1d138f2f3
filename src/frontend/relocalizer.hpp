#pragma once
// Finding a frame's pose against a keyframe with no starting point to align from (after a covered lens
// or a gap in the input, the camera is wherever it went meanwhile): ORB features of the frame matched
// to the keyframe's, which take the depths of the keyframe's points next to them, then a
// perspective-n-point solve in RANSAC (OpenCV). The direct alignment refines what this finds.
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "core/camera.hpp"
#include "core/reflect.hpp"
#include "core/se3.hpp"
#include "map/keyframe.hpp"

namespace eds {

struct RelocalizerConfig {
  int features = 1500;      // ORB features detected in each image
  int depth_radius_px = 3;  // a keyframe feature takes the depth of its nearest point this close
  int max_hamming = 64;     // of a match (of 256 bits)
  double ratio = 0.8;       // best match / second best, Hamming distances
  double ransac_px = 2.0;   // reprojection error of a PnP inlier
  int min_inliers = 15;     // and at least this fraction of the matches:
  double min_inlier_fraction = 0.25;
};

EDS_FIELDS(RelocalizerConfig, features, depth_radius_px, max_hamming, ratio, ransac_px, min_inliers,
           min_inlier_fraction)

// ORB features of two images matched one to one (a match must be distinctly the best of its image's).
struct FeatureMatchConfig {
  int features = 1500;   // detected in each image
  int max_hamming = 64;  // of a match (of 256 bits)
  double ratio = 0.8;    // best match / second best, Hamming distances
};

EDS_FIELDS(FeatureMatchConfig, features, max_hamming, ratio)

struct FeatureMatches {
  std::vector<cv::Point2f> a, b;  // a[i] in the first image matches b[i] in the second
};

// `a`, `b`: CV_32F in [0, 1] or 8-bit.
FeatureMatches matchFeatures(const cv::Mat& a, const cv::Mat& b, const FeatureMatchConfig& cfg);

struct Relocalization {
  bool ok = false;  // enough matches agree on T_f_kf
  SE3 T_f_kf;
  int matches = 0, inliers = 0;
};

// `frame`: undistorted, CV_32F in [0, 1] or 8-bit; `kf.points` with inverse depths (0: unknown, not
// used); `pinhole`: the undistorted camera.
Relocalization relocalize(const Keyframe& kf, const cv::Mat& frame, const CameraModel& pinhole,
                          const RelocalizerConfig& cfg);

}  // namespace eds
