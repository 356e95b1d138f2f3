#pragma once
// The frame half of the front-end: every frame is aligned to the newest keyframe reference
// (FrameTracker; seeded by a constant-velocity prediction, or by the event tracker's pose in EDS), DSO's
// optical-flow keyframe rule decides when to hand a keyframe to the back-end (BackendWorker), and
// references the back-end publishes are taken up at the next frame.
#include <optional>

#include "frontend/frame_tracker.hpp"
#include "frontend/relocalizer.hpp"
#include "system/backend_worker.hpp"
#include "system/odometry.hpp"

namespace eds {

// RMS pixel flow of the keyframe's points under T_f_kf, and of its translation alone; the fraction
// of points still in view.
struct Flow {
  double rt = 0, t = 0, in_view = 0;
};
Flow flowOf(const std::vector<KeyframePoint>& pts, const SE3& T_f_kf, const CameraModel& cam);

// The alignment from ORB features must keep this share of the other alignment's residuals.
constexpr double kFeatureMinResidualShare = 0.8;

// Whether a frame's alignment from ORB features replaces the best of the other starts: it converged,
// and they failed or it fits clearly better (residual RMSE under max_rmse_ratio times theirs) over
// nearly as many points.
bool featureAlignmentWins(const FrameTrackResult& features, const FrameTrackResult& best,
                          double max_rmse_ratio);

class FrameFrontend {
 public:
  // `clock` (may be null): the calling thread's stage clock, passed on to the back-end worker;
  // `first_keyframe_id`: the id of its first keyframe (ids go on over map segments).
  FrameFrontend(const CameraModel& cam, const OdometryConfig& cfg, OdometryResult& res,
                StageClock* clock = nullptr, int first_keyframe_id = 0);

  // Hands a keyframe to the back-end (mapping + BA). Returns the pose of the keyframe's frame: the
  // optimized one when the back-end ran at once (synchronous), else the given one.
  SE3 addKeyframe(TimeNs t, const cv::Mat& img, const SE3& T_w_new, double a, double b,
                  std::vector<KeyframePoint> pts_with_depth = {});
  // Tracks a frame; returns its pose. `prior`: a pose for the frame from elsewhere (the event tracker),
  // tried first. Adds a keyframe when the policy asks.
  SE3 track(TimeNs t, const cv::Mat& img, const SE3* prior = nullptr);
  bool lastTrackOk() const { return last_ok_; }
  // The last frame's pose came from the alignment from ORB features (the other starts fitted worse).
  bool lastFromFeatures() const { return from_features_; }
  // A frame kept out of keyframes and the map (the quality check refused it; the caller has prepared it
  // with normalizeRefusedFrame), aligned from `prior` (the events' pose) or else the constant-velocity
  // prediction, with brightness (α, β) from (1, 0). Its pose when the alignment succeeded on enough
  // residuals and landed within the frame_quality bounds of its start (it then becomes the last pose),
  // else nullopt. The caller has called awaitPendingKeyframe(true) for the frame.
  std::optional<SE3> trackRefused(TimeNs t, const cv::Mat& img, const SE3* prior);
  // What every frame does first, usable or not: takes up the reference the back-end published, and
  // waits for it when a keyframe is pending (wait_for_keyframe) or there is none yet. With
  // early_reference a usable frame waits until the keyframe is mapped; `adjusted`: until its bundle
  // adjustment is done, for a refused frame, after which the events alone carry the pose.
  void awaitPendingKeyframe(bool adjusted = false);
  // The frame's pose with no starting point (features against the newest reference, then the direct
  // alignment from there, all levels); on success the track goes on from it, at rest. nullopt when
  // neither finds the frame. `found` says how (matches and inliers), or why not.
  std::optional<SE3> relocalize(TimeNs t, const cv::Mat& img, std::string& found);

  void setLast(TimeNs t, const SE3& T_w_f);
  // The pose at t (a frame's time) if the last two frames' motion goes on (the last pose with
  // only one), the last motion scaled to the time since the last frame.
  SE3 constantVelocityPose(TimeNs t) const;
  static constexpr double kMaxCvSteps = 4.0;  // the most steps of the last motion it extrapolates
  void setLastBrightness(double a, double b) { a_last_ = a, b_last_ = b; }
  // Takes the newest reference the back-end published (waiting for it if asked); true if it changed.
  bool adoptReference(bool wait);
  // The current tracking reference (keyframe image, points with inverse depth) and its pose.
  const Keyframe& reference() const { return ref_; }
  int referenceId() const { return ref_id_; }
  // Counts the references taken up (a keyframe's optimized reference follows its preliminary one
  // under the same id).
  int referenceVersion() const { return reference_version_; }
  bool referencePreliminary() const { return ref_preliminary_; }
  const SE3& T_w_kf() const { return T_w_kf_; }

  BackendWorker& worker() { return worker_; }

  // A keyframe handed to the threaded back-end and not yet published as the reference: the policy
  // measures the motion from it (the reference's points seen from it), not from the reference, or
  // the frame after every keyframe would ask for one more and wait for the back-end.
  struct Pending {
    bool active = false;
    int id = -1;  // the id the back-end will publish it with
    TimeNs t = -1;
    SE3 T_w_kf;
    double a = 0;
    std::vector<KeyframePoint> points;
  };
  // That keyframe, or null when none is pending.
  const Pending* pendingKeyframe() const { return pending_.active ? &pending_ : nullptr; }

 private:
  bool keyframeDueBeforeNextFrame(const SE3& T_f_kf) const;
  // The keyframe policy; `scale` > 1 widens its bounds on the flows (`scale` times larger).
  bool wantKeyframe(const Flow& fl, double alpha, double scale = 1.0) const;
  // Without wait_for_keyframe, a keyframe wanted while the back-end is busy waits for a later frame
  // only while the frame's flows from the tracking reference are within this many times the policy's
  // bounds (and its other bounds hold: points in view, brightness change).
  static constexpr double kDeferLimit = 3.0;
  FrameTrackResult align(TimeNs t, const cv::Mat& img, const SE3* prior, SE3& T_f_kf, double& alpha,
                         double& beta);
  void alignFromFeatures(TimeNs t, const cv::Mat& img, FrameTrackResult& tr, SE3& T_f_kf, double& alpha,
                         double& beta);

  CameraModel cam_;
  const OdometryConfig& cfg_;
  OdometryResult& res_;
  BackendWorker worker_;
  FrameTracker tracker_;
  Keyframe ref_;
  int ref_id_ = -1, reference_version_ = 0;
  bool ref_preliminary_ = false;
  double ref_depth_ratio_ = 1.0;  // 90th / 10th percentile of the reference's depths
  bool has_ref_ = false, last_ok_ = false, from_features_ = false;
  SE3 T_w_kf_;
  double a_kf_ = 0, b_kf_ = 0, alpha_ = 1.0, beta_ = 0.0;
  double a_last_ = 0, b_last_ = 0;  // absolute brightness of the last frame
  double last_rmse_ = 1e9;          // of the last successful alignment
  int last_residuals_ = 0;          // and its residual count
  SE3 last_T_w_f_, prev_T_w_f_;
  TimeNs last_t_ = 0, prev_t_ = 0;
  bool has_last_ = false, has_prev_ = false;
  Pending pending_;
  void setPending(int id, TimeNs t, const SE3& T_w_new, double a);
};

}  // namespace eds
