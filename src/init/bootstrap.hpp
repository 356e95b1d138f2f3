#pragma once
// Bootstrap (paper §3.4, DSO's coarse initializer): the first frame with enough texture becomes the
// reference; its selected points start at a constant inverse depth of 1. Every following frame is
// aligned to it (coarse-to-fine, FrameTracker) and then pose and inverse depths are refined jointly by
// a two-frame photometric bundle adjustment, in which a weak prior holds each inverse depth near its
// start while the baseline is too short to observe it. Once the parallax caused by translation is
// large enough (and the alignment good), the map is initialized: inverse depths are scaled to a mean
// of 1 (monocular scale is arbitrary), with the translations to match.
//
// Alongside, corners are tracked (GeometricInit). Constant initial depth suits planes but not scenes
// with depth structure and large motion between the first frames (the real slider sequences); when the
// tracks show a non-planar scene with enough parallax, the essential matrix gives the pose and
// triangulation the depths (filled into the reference's points), the two-frame photometric BA refines
// them, and the frames in between are aligned to the new map. The photometric path may only declare
// success on a frame whose tracks show the scene to be planar (or when there are too few tracks to
// tell): a verdict from an earlier frame may have come from a rotation, which a homography explains too.
#include <optional>
#include <vector>

#include "backend/photometric_ba.hpp"
#include "core/camera.hpp"
#include "core/reflect.hpp"
#include "core/time.hpp"
#include "frontend/frame_tracker.hpp"
#include "frontend/point_selection.hpp"
#include "init/geometric_init.hpp"
#include "map/keyframe.hpp"

namespace eds {

struct BootstrapConfig {
  PointSelectionConfig points{
      .tile = 8, .fraction = 0.06, .min_gradient = 0.01, .border = 4, .max_points = 1500};
  FrameTrackerConfig tracker;
  BaConfig ba{.iterations = 6};
  int ba_levels = 1;  // pyramid levels of the two-frame BA (1: full resolution only)
  // Views in the bundle adjustment that completes the initialization: the reference, the last frame
  // and frames spread between (2: the reference and the last frame alone).
  int final_views = 2;
  double depth_prior_weight = 0.02;  // ½ w (ρ − 1)² per point; intensity units² per (1/m)²
  double min_parallax_px = 8.0;      // RMS pixel flow of the translation alone, to declare success
  // With frames this far apart (s) or more, this much parallax is enough: waiting for more costs a
  // second a frame, and a camera that mostly turns takes the reference out of view before it comes.
  double sparse_frame_interval_s = 0.4;
  double min_parallax_px_sparse = 4.0;
  int min_points = 300;       // a reference needs this many selected points (texture)
  int min_frames = 2;         // frames after the reference before success can be declared
  int min_frames_sparse = 1;  // the same when the frame came sparse_frame_interval_s or more after the last
  int max_frames = 50;        // no success by then: the newest frame becomes the reference
  double max_parallax_step_px = 25;  // parallax growing faster than this per frame: diverged, restart
  double max_rmse = 0.05;            // two-frame residual RMS (intensity) above this: restart
  // A frame whose fit is worse than the frame's before it (same reference) on both counts, its
  // residual RMS more than max_rmse_growth times and its inliers fewer than min_inlier_share times
  // that frame's, is no success either: it lies far from the last (frames dropped in between) and the
  // fit found a wrong basin. (Either alone also flags good frames: the RMS grows with the parallax,
  // and the inliers fall where the camera moves much between sparse frames.)
  double max_rmse_growth = 1.5;
  double min_inlier_share = 0.6;
  // A frame sparse_frame_interval_s or more after the one before whose fit keeps fewer than this
  // fraction of the reference's points as inliers: restart.
  double min_inlier_fraction_sparse = 0.4;
  // |a| of the frame's affine brightness (I ≈ e^{-a} I_ref + b) above this: the alignment explained a
  // wrong geometry with a change of exposure (a pure rotation can do that); restart
  double max_log_brightness = 1.0;
  double max_intensity = 0.98;  // pixels this bright (saturated) are not selected
  double min_intensity = 0.02;  // nor pixels this dark
  bool geometric = true;        // the essential-matrix path for non-planar scenes (see below)
  GeometricInitConfig geometric_init;
  DepthFillConfig fill{.max_distance_px = 15, .neighbours = 3};
  void validate() const;
};

EDS_FIELDS(BootstrapConfig, points, tracker, ba, ba_levels, final_views, depth_prior_weight, min_parallax_px,
           sparse_frame_interval_s, min_parallax_px_sparse, min_points, min_frames, min_frames_sparse,
           max_frames, max_parallax_step_px, max_rmse, max_rmse_growth, min_inlier_share,
           min_inlier_fraction_sparse, max_log_brightness, max_intensity, min_intensity, geometric,
           geometric_init, fill)

struct BootstrapFrame {
  TimeNs t = 0;
  SE3 T_ref_c;  // pose of the frame in the reference (world of the bootstrap)
  double a = 0, b = 0;
};

class Bootstrap {
 public:
  Bootstrap(const CameraModel& pinhole, BootstrapConfig cfg);

  // Feeds the next frame (undistorted, CV_32F in [0, 1]). Returns true when the map is initialized;
  // after that the accessors below hold the result and further calls throw.
  // `hint`, if given, is a guess of the frame's pose in the reference (T_c_ref; from the events, which
  // track the camera between frames): the alignment starts from it as well as from the
  // constant-velocity prediction and keeps the better. With frames far apart (the second one 0.4-1 s
  // after the first) the prediction is far off and the hint is what brings the frame into the basin.
  bool add(TimeNs t, const cv::Mat& image, const SE3* hint = nullptr);
  bool hasReference() const { return has_ref_; }

  bool done() const { return done_; }
  // The reference keyframe (points with inverse depths, mean 1) and every frame since, the last one
  // being the frame that completed the initialization.
  const Keyframe& reference() const { return ref_; }
  const std::vector<BootstrapFrame>& frames() const { return frames_; }
  const cv::Mat& lastImage() const { return last_image_; }
  int restarts() const { return restarts_; }
  double parallax() const { return parallax_; }
  double rmse() const { return rmse_; }
  bool usedGeometric() const { return geometric_used_; }

 private:
  bool setReference(TimeNs t, const cv::Mat& image);
  bool tryGeometry(TimeNs t, const cv::Mat& image, const SE3* hint);
  bool alignToReference(const cv::Mat& image, const SE3* hint, SE3& T_c_ref, double& alpha,
                        double& beta) const;
  BaStats twoFrameBa(const cv::Mat& image, const SE3& T_c_ref, double alpha, double beta,
                     std::vector<BaFrame>& fr, std::vector<BaPoint>& pts) const;
  double translationParallax(const SE3& T_c_ref) const;

  CameraModel cam_;
  BootstrapConfig cfg_;
  Keyframe ref_;
  bool initFromGeometry(TimeNs t, const cv::Mat& image, const GeometricInitResult& g);
  // Mean inverse depth 1 (translations to match); the frames' images are no longer needed.
  void normalizeScale();
  // Frames 1 .. count-1 (their images kept) aligned to the reference's current map; the frames'
  // present poses give the starts, their translations times `scale`; the last frame is at T_ref_last.
  void realignFrames(TimeNs t_last, const SE3& T_ref_last, double scale, std::size_t count,
                     const std::vector<std::optional<SE3>>& T_ref_c_tracks = {});
  // Aligns frame k to the map from each start (motion, geodesic, corner tracks); keeps the best fit.
  void alignFromStarts(const FrameTracker& tracker, std::size_t k, const std::vector<SE3>& starts);
  // The reference's depths and final_views - 1 of the frames since (the last one, image `last_image`,
  // among them) in one bundle adjustment; then every frame but the last (those in it as well) aligned
  // again to its depths.
  void refineWithViews(const cv::Mat& last_image);
  // After the photometric path failed: keeps the frame for the geometric path, or restarts.
  bool keepForGeometry(TimeNs t, const cv::Mat& image);

  enum class GeoState { kPending, kPlanar, kUnavailable };
  GeometricInit geo_;
  GeoState geo_state_ = GeoState::kPending;
  std::vector<cv::Mat> images_;  // frames since the reference (for re-alignment after the geometric path)
  bool has_ref_ = false, done_ = false, geometric_used_ = false, photometric_failed_ = false;
  std::vector<BootstrapFrame> frames_;
  cv::Mat last_image_;
  int restarts_ = 0;
  double parallax_ = 0, rmse_ = 0;
  double previous_rmse_ = 0;  // of the last frame kept for this reference (0: none yet)
  int previous_inliers_ = 0;
};

}  // namespace eds
