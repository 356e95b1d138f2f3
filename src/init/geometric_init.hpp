#pragma once
// The geometric fallback of the bootstrap: corners of the reference frame (Shi-Tomasi) are tracked
// frame to frame by pyramidal Lucas-Kanade with a forward-backward check; once their median flow is
// large enough, an essential matrix (RANSAC; MAGSAC++ when RANSAC's leaves too few tracks in front of
// both cameras) gives the relative pose and triangulation the depths.
// A homography that explains nearly as many tracks as the essential matrix means a planar (or
// rotation-only) configuration, where the essential matrix degenerates: the result says so and the
// caller keeps the photometric initializer, which handles planes.
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "core/camera.hpp"
#include "core/reflect.hpp"
#include "core/se3.hpp"
#include "frontend/relocalizer.hpp"
#include "mapping/depth_fill.hpp"

namespace eds {

struct GeometricInitConfig {
  int max_features = 500;
  double quality = 0.005;         // Shi-Tomasi quality level
  double min_distance = 6;        // between corners, px
  double min_flow_px = 12;        // median flow needed before the pose is estimated
  int min_tracks = 60;            // fewer live tracks: no initialization from this reference
  double ransac_px = 1.0;         // inlier threshold, px
  double planar_ratio = 0.9;      // homography inliers ≥ this × essential inliers: planar
  double max_reproj_px = 2.0;     // triangulated points must reproject this well in both frames
  double min_parallax_deg = 1.5;  // median angle between the two rays of the triangulated points
  // The same for a frame that came long after the one before: waiting a second more for parallax
  // costs more than a slightly narrower baseline.
  double min_parallax_deg_sparse = 1.0;
  // Corners the optical flow loses between sparse frames are tracked again from where the events' pose
  // puts them.
  bool from_events = true;
  // On such tracks MAGSAC++'s essential matrix (taken when RANSAC's fails the cheirality vote) must move
  // the camera within this angle of the events' translation direction: that direction is rough (20-40
  // deg off), but MAGSAC++'s wrong minorities there were 90-150 deg off.
  double max_events_direction_deg = 60.0;
  // When that leaves too few tracks too, the reference's ORB features matched to the frame's take their
  // place for that frame (MAGSAC++'s result on them is held to the events' direction as well), on frames
  // this long after the one before: closer together, the photometric path initialized on its own within
  // 2 s and more accurately than such matches.
  bool from_features = true;
  double features_min_interval_s = 0.75;
  FeatureMatchConfig features;
  // Where the matches themselves are the tracks (too few corners followed them), the triangulation angle
  // they must reach: off by up to a pixel of ORB's coarser levels, such matches on a textured wall gave
  // essential matrices that took most of the translation for rotation (measured parallax 1-3 deg, right
  // ones 10-36 deg).
  double min_parallax_deg_matches = 5.0;
};

EDS_FIELDS(GeometricInitConfig, max_features, quality, min_distance, min_flow_px, min_tracks, ransac_px,
           planar_ratio, max_reproj_px, min_parallax_deg, min_parallax_deg_sparse, from_events,
           max_events_direction_deg, from_features, features_min_interval_s, features,
           min_parallax_deg_matches)

struct GeometricInitResult {
  bool planar = false;
  int inliers = 0;
  double parallax_deg = 0;             // median triangulation angle
  SE3 T_c_ref;                         // translation of unit norm
  std::vector<ProjectedPoint> points;  // triangulated, in the reference: pixel and inverse depth
  // The frames added before this one (in order, the reference's successors): each one's pose from the
  // triangulated points and where its tracks were in it (PnP), in the same scale; none where that fails.
  std::vector<std::optional<SE3>> T_c_ref_before;
};

class GeometricInit {
 public:
  GeometricInit(const CameraModel& pinhole, GeometricInitConfig cfg);
  // Starts over with a new reference (undistorted, CV_32F in [0, 1]).
  void reset(const cv::Mat& ref_image);
  // Tracks the corners into the next frame; a result once the flow is large enough. `sparse`: the frame
  // came long after the one before (the sparse parallax bound applies). `hint`: the frame's pose from the
  // events (T_c_ref, the reference at unit depth), where the corners start if they are lost without it.
  // `interval_s`: the time since the frame before (whether matched features may replace lost tracks).
  std::optional<GeometricInitResult> add(const cv::Mat& image, bool sparse = false, const SE3* hint = nullptr,
                                         double interval_s = 0);
  int tracks() const { return static_cast<int>(cur_.size()); }
  // Whether the last frame's tracks are those started from the events' pose or matched features: they
  // serve that frame alone.
  bool tracksReseeded() const { return from_events_ || from_features_; }

 private:
  CameraModel cam_;
  GeometricInitConfig cfg_;
  std::size_t track(const std::vector<cv::Mat>& from_pyr, const std::vector<cv::Point2f>& from,
                    const std::vector<cv::Mat>& pyr, cv::Size size, const std::vector<cv::Point2f>* predicted,
                    std::vector<cv::Point2f>& next, std::vector<unsigned char>& keep) const;
  std::vector<cv::Point2f> predict(const SE3& T_c_ref) const;
  bool advance(const cv::Mat& image, bool sparse, const SE3* hint, double interval_s);
  void matchFeaturesInstead(const cv::Mat& gray, const std::vector<cv::Mat>& pyr);
  std::vector<cv::Point2f> flowFromMatches(const FeatureMatches& m) const;
  bool twoViewMotion(GeometricInitResult& res, const SE3* hint, cv::Mat& mask_e, Mat3& Re, Vec3& te) const;
  // Poses of the frames before the current one, from the triangulated points (indexed like ref_).
  std::vector<std::optional<SE3>> posesBefore(const std::vector<int>& triangulated,
                                              const std::vector<Vec3>& X_ref) const;

  static constexpr int kLevels = 3;  // pyramid levels of the corner tracking above the image
  inline static const cv::Size kWindow{21, 21};
  std::vector<cv::Mat> prev_pyr_;  // the last image's pyramid
  std::vector<cv::Point2f> ref_, cur_;
  // Each live track's corner index in the reference, and every frame's track positions by that index
  // (NaN once lost): the frames in between get their poses from them once the depths are known.
  std::size_t corners_ = 0;
  bool from_events_ = false, from_features_ = false;
  bool raw_matches_ = false;           // the tracks are the feature matches themselves
  cv::Mat ref8_;                       // the reference image, 8-bit (for its features)
  std::vector<cv::Mat> ref_pyr_;       // and its pyramid
  std::vector<cv::Point2f> corners0_;  // all of the reference's corners
  std::vector<int> ids_;
  std::vector<std::vector<cv::Point2f>> seen_;
};

}  // namespace eds
