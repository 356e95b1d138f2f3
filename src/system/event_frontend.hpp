#pragma once
// The event half of the front-end (paper §3.2): every event frame is tracked against the newest
// keyframe reference by the EGM tracker, giving event-rate poses between frames. The reference is the
// back-end's (its window points projected into the newest keyframe); the keyframe's other selected
// pixels take the inverse depth of the nearest of those points (k-d tree), so the tracker sees the
// paper's 10-15 % of pixels. Frames, when they come, correct the estimate (they are sharper).
#include <array>
#include <optional>
#include <string>

#include "core/reflect.hpp"
#include "frontend/event_frame.hpp"
#include "frontend/event_tracker.hpp"
#include "frontend/point_selection.hpp"
#include "mapping/depth_fill.hpp"

namespace eds {

// The motion prior of each event frame: a constant-velocity extrapolation of the last two tracked
// frames' poses. Its standard deviation grows with the time dt since the last frame:
//     σ(dt) = σ0 (1 + √2 dt / Δ) + ½ a dt²
// (Δ: time between the two frames; the middle term is the velocity's error from two poses that are
// each σ0 off). Translations are fractions of the reference's median depth. Far from a frame the
// prior fades and the events alone decide; between frames at video rate it holds the direction
// that one event frame cannot tell (lateral translation vs rotation) to what the frames say.
struct MotionPriorConfig {
  bool enabled = true;
  double sigma_translation = 1e-4;  // σ0: fraction of the median depth
  double accel = 0.3;               // a: fractions of the median depth per s²
  double sigma_rotation = 5e-4;     // σ0: rad
  double ang_accel = 10.0;          // a: rad/s²
  double max_gap_s = 0.5;           // frames farther apart than this predict nothing
  void validate() const;
};

EDS_FIELDS(MotionPriorConfig, enabled, sigma_translation, accel, sigma_rotation, ang_accel, max_gap_s)

// The lost-track check: an event frame whose correlation n̂·n falls below min_correlation_ratio of
// the median of the last five event frames tracked on the same reference, or whose cost rises above
// max_cost_ratio times theirs, is a failure (its pose is not kept). A fixed floor cannot tell: a good
// run on the simulated desk has a sixth of its event frames below 0.85. 0 turns a check off.
struct LostTrackConfig {
  double min_correlation_ratio = 0.75;
  double max_cost_ratio = 2.0;
  void validate() const;
};

EDS_FIELDS(LostTrackConfig, min_correlation_ratio, max_cost_ratio)

// The points the event tracker solves per second: while frames come at least every max_frame_gap_s, a
// reference gets at most points_per_second divided by the recent event-frame rate (evenly thinned).
// Fast event frames overlap and measure the same motion, and frames that close anchor their poses, so
// the work per second stops growing with the event rate. Between frames farther apart each event frame
// carries the pose alone, and every point is kept. points_per_second 0: every point, always.
struct PointBudgetConfig {
  double points_per_second = 5e5;
  double max_frame_gap_s = 0.1;
  void validate() const;
};

EDS_FIELDS(PointBudgetConfig, points_per_second, max_frame_gap_s)

// Points that stay outliers while frames are sparse (EventTracker::setPersistentOutliers): a point
// whose residual is beyond `sigmas` robust σ in `frames` event frames in a row is left out until the
// next reference. A second between frames, near objects sweep over the reference's far points; with
// frames closer together the reference is renewed first, and left-out points cost more runs than they
// save (measured at 2 and 5 FPS). The rule applies while the last two usable frames are more than
// min_frame_gap_s apart, or none came for that long. frames 0: never.
struct PersistentOutlierConfig {
  int frames = 5;
  double sigmas = 2.5;
  double min_frame_gap_s = 0.75;
  void validate() const;
};

EDS_FIELDS(PersistentOutlierConfig, frames, sigmas, min_frame_gap_s)

struct EventFrontendConfig {
  EventTrackerConfig tracker;
  // Selection on the keyframe's log gradient. Beyond a DAVIS346's pixel count the tracker keeps the
  // point count of that size (spread the same way): its work per event frame stops growing with the
  // sensor, at no measured cost in accuracy at 640x480.
  PointSelectionConfig points{.full_density_pixels = 1e5};
  DepthFillConfig fill{.max_distance_px = 1, .neighbours = 3};
  double depth_median_px = 10.0;  // median filter of the reference's inverse depths (0: off)
  PointBudgetConfig point_budget;
  MotionPriorConfig motion_prior;
  LostTrackConfig lost_track;
  PersistentOutlierConfig persistent_outliers;
};

EDS_FIELDS(EventFrontendConfig, tracker, points, fill, depth_median_px, point_budget, motion_prior,
           lost_track, persistent_outliers)

class EventFrontend {
 public:
  EventFrontend(const CameraModel& pinhole, EventFrontendConfig cfg);

  // A new reference: keyframe intensity image and points with inverse depths, and its pose. The
  // points are the back-end's: the keyframe's selected pixels next to one of them take its depth.
  void setReference(const Keyframe& ref, const SE3& T_w_kf);
  // A reference whose points are already the selected pixels, each with its depth (known depth).
  void setDenseReference(const Keyframe& ref, const SE3& T_w_kf);
  // A frame at time t that became a keyframe the threaded back-end is still mapping: tracked against
  // at once (image `img`, pose T_w_f as tracked, `points` the reference's points seen from it), until
  // the back-end publishes that keyframe. A reference older than t is not taken meanwhile.
  void setProvisionalReference(int id, TimeNs t, const cv::Mat& img, const SE3& T_w_f,
                               const std::vector<KeyframePoint>& points);
  // The reference's image replaced by a sharper one of the same view (its frame deblurred with the
  // events of its exposure): the points are selected and filled again on it, the estimate stays. Only
  // for the reference at time t made by setReference or setProvisionalReference.
  void sharpenReference(TimeNs t, const cv::Mat& img);
  bool hasReference() const { return has_ref_; }
  // The reference as tracked: its image, and its points with their (filtered) inverse depths.
  const Keyframe& reference() const { return ref_; }
  // The keyframe the event poses are composed with (T_w_ef = T_w_kf·T_kf_ef) and its pose: the
  // reference, a provisional one included (its id is the one the back-end will publish it with).
  int referenceId() const { return ref_id_; }
  const SE3& T_w_kf() const { return T_w_kf_; }
  // Tracks an event frame from the prior (if given) or a constant-velocity prediction. The pose
  // (T_w_ef), or nullopt when the frame cannot be tracked (the estimate then stays as it was) or the
  // lost-track check fails (the estimate follows the solve; `failure` says why).
  std::optional<SE3> track(const EventFrame& ef, const SE3* prior, std::string* failure = nullptr);
  // An event frame between two frames already tracked (T_w_a at t_a, T_w_b at t_b; the buffered event
  // frames of the bootstrap): it starts from the previous event frame's pose when that lies between
  // the same frames, else from their geodesic interpolation, which is also its motion prior (frames
  // at most motion_prior.max_gap_s apart), with the σ of an interpolation under bounded acceleration,
  // σ0 + ½ a (t−t_a)(t_b−t).
  std::optional<SE3> trackBetween(const EventFrame& ef, TimeNs t_a, const SE3& T_w_a, TimeNs t_b,
                                  const SE3& T_w_b, std::string* failure = nullptr);
  // A better pose at time t (a tracked frame): the next event frame starts from it, and the last two
  // make the motion prior. A frame the quality check refused (`usable` false) anchors the pose but
  // renews no reference, so the point budget does not count it.
  void correct(TimeNs t, const SE3& T_w_c, bool usable = true);
  // Starts again from T_w_c at rest (after a lost track: from the last good pose).
  void restartFrom(const SE3& T_w_c) {
    T_ef_kf_ = T_w_c.inverse() * T_w_kf_;
    nu_.setZero();
    t_prev_ = -1;
  }
  int numPoints() const { return static_cast<int>(tracker_.numPoints()); }
  // The last solve's correlation n̂·n of the event frame with the model's prediction.
  double lastCorrelation() const { return last_correlation_; }
  // Points of the reference inside the last tracked event frame, and the last pose relative to the
  // reference (for a keyframe policy).
  int lastPointsInView() const { return last_in_view_; }
  int pointsInView(const SE3& T_ef_kf) const {
    return tracker_.pointsInView(T_ef_kf, cam_.width, cam_.height);
  }
  const SE3& T_ef_kf() const { return T_ef_kf_; }
  double referenceMedianDepth() const { return median_depth_; }
  // The model's prediction ΔL̂ of the last tracked event frame, at its pose (EventTracker::predictedImage).
  cv::Mat lastPrediction() const { return tracker_.predictedImage(T_ef_kf_, nu_, cam_.width, cam_.height); }

 private:
  CameraModel cam_;
  EventFrontendConfig cfg_;
  EventTracker tracker_;
  bool has_ref_ = false;
  Keyframe ref_;
  std::vector<KeyframePoint> ref_source_;  // the points the reference's were filled from
  int ref_id_ = -1;
  SE3 T_w_kf_;
  TimeNs provisional_t_ = -1;  // time of the provisional reference's frame; -1: none
  SE3 T_ef_kf_, T_prev_;       // current estimate and the one before (constant-velocity prediction)
  Vec6 nu_ = Vec6::Zero();
  TimeNs t_last_ = -1, t_prev_ = -1;
  bool corrected_ = false;
  double median_depth_ = 1.0;  // of the reference's points
  double last_correlation_ = 0;
  int last_in_view_ = 0;
  // Correlations and costs of the last event frames tracked on this reference (ring buffers).
  static constexpr std::size_t kRecent = 5;
  std::array<double, kRecent> recent_corr_{}, recent_cost_{};
  std::size_t recent_n_ = 0;
  // Event frames passed over right before one (load shedding) from which it is solved coarse-to-fine.
  static constexpr std::size_t kPassedForCoarseToFine = 3;
  // Times of the last event frames given to the tracker (ring buffer), for their rate.
  static constexpr std::size_t kRateWindow = 16;
  std::array<TimeNs, kRateWindow> ef_times_{};
  std::size_t ef_count_ = 0;
  TimeNs t_u0_ = -1, t_u1_ = -1;      // the last two usable frames
  bool thinned_ = false;              // the tracker has a subset of the reference's points
  int maxReferencePoints() const;     // 0: all
  bool framesSparse(TimeNs t) const;  // the persistent-outlier rule applies at time t
  void setTrackerReference();
  // The last two frames' poses (world), for the motion prior.
  TimeNs t_f0_ = -1, t_f1_ = -1;
  SE3 T_w_f0_, T_w_f1_;
  // False (the previous reference kept) when kf has too few points to be tracked against.
  bool adopt(Keyframe kf, const SE3& T_w_kf, bool provisional = false);
  // The points (keyframe pixels with inverse depth) and the keyframe's selected pixels next to them.
  void addFilledPoints(Keyframe& kf, const std::vector<KeyframePoint>& points) const;
  // The move of the world estimate that puts the corrected frame at t_kf onto its keyframe's pose
  // T_w_kf, applied to the last two frames' poses; nullopt when neither is at t_kf or it is exactly
  // there.
  std::optional<SE3> worldMoveTo(TimeNs t_kf, const SE3& T_w_kf);
  SE3 moveWorld(const SE3& T_new_old);  // moves the frames' poses; returns the move
  std::string lostTrack(const TrackResult& tr) const;
  bool motionPrior(TimeNs t, PosePrior& prior) const;
  Vec6 priorSigma(double dt, double grow) const;
  std::optional<SE3> solve(const EventFrame& ef, const SE3& T_init, int levels, const PosePrior* motion,
                           std::string* failure);
};

}  // namespace eds
