#pragma once
// EventTracker (paper Eq. 7): the pose of the event camera relative to the keyframe, T_ef_kf, and the
// camera velocity direction ν minimize the Huber norm of
//     r = ΔL̂/‖ΔL̂‖ − ΔL/‖ΔL‖
// over the keyframe's points, where ΔL̂_i = a_i · ν (egm.hpp) and ΔL_i is the event frame sampled
// (bicubic) where point i lands in the event camera. Both norms run over the points in view, as Eq. 7
// says (the authors' code normalized per residual block, a side effect of threading).
//
// Solver: our own Levenberg-Marquardt on 12 parameters (pose increment on the left, velocity
// additive then renormalized: only its direction matters). The normalization couples all residuals,
// but the Jacobian P·D with P = (I − nnᵀ)/‖m‖ is formed as D − n (nᵀD), O(points), never N×N.
// A 12x12 normal-equation solve per iteration needs no sparse machinery, and one pass over the
// points builds it: no per-residual-block overhead.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/reflect.hpp"
#include "core/se3.hpp"
#include "frontend/egm.hpp"
#include "frontend/event_frame.hpp"
#include "map/keyframe.hpp"

namespace eds {

struct EventTrackerConfig {
  int max_iterations = 12;  // per level
  // A solve ends when a step moves the points by less than this (px), or lowers the cost by < 1e-4.
  double converged_step_px = 0.02;
  int levels = 3;              // coarse-to-fine: event frame blurred by 0, 1.5, 3 px
  double huber_initial = 0.1;  // on normalized residuals; then 1.345 * 1.4826 * MAD after each solve
  bool adapt_huber = true;
  double border = 2.0;           // px: bicubic sampling needs a margin
  double set_margin = 4.0;       // px: a solve uses the points this far inside the border at its start
  int min_points = 30;           // fewer points in view: the frame cannot be tracked
  double min_correlation = 0.2;  // n̂·n below this after the solve: reported as a failure
  double lambda_initial = 1e-3;
  // The EGM rows made at each event frame's starting pose (egmRowAtView) rather than at the keyframe.
  bool egm_at_view = true;
  void validate() const;
};

EDS_FIELDS(EventTrackerConfig, max_iterations, converged_step_px, levels, huber_initial, adapt_huber, border,
           set_margin, min_points, min_correlation, lambda_initial, egm_at_view)

// A Gaussian prior on the pose (a motion model's prediction). Its error is the left twist
// e = log(T_ef_kf · T_prior⁻¹) = (translation, rotation), with standard deviations `sigma` in metres and
// radians. One event frame of a scene at roughly one depth barely tells a lateral translation from
// the rotation that moves the image the same way; the prior pins that direction where the data cannot.
// The data term's weight is its residuals' variance (from the MAD of the last solve), so the prior
// keeps its meaning whatever the number of points or the event frame's contrast.
struct PosePrior {
  SE3 T_ef_kf;
  Vec6 sigma = Vec6::Constant(1.0);
};

// The prior's share of the tracker's 12-parameter normal equations (ξ, ν) at T_ef_kf: with
// info = scale / σ², H += diag(info) and g += info ∘ e on the pose block, taking e(exp(ξ) T) ≈ e(T) + ξ
// as the small errors a prior is meant for allow. `scale` is the data term's residual variance.
// Returns the prior's cost ½ scale eᵀ Σ⁻¹ e.
double accumulatePosePrior(const PosePrior& prior, double scale, const SE3& T_ef_kf,
                           Eigen::Matrix<double, 12, 12>& H, Eigen::Matrix<double, 12, 1>& g);

struct TrackResult {
  bool ok = false;
  int iterations = 0;
  int points_in_view = 0;
  double cost = 0;
  double correlation = 0;  // n̂·n at the solution: 1 = the prediction explains the events perfectly
  std::string failure;     // why not ok
};

class EventTracker {
 public:
  EventTracker(const CameraModel& pinhole, EventTrackerConfig cfg);

  // Uses the keyframe's points that have an inverse depth. Throws std::invalid_argument if none.
  // With max_points > 0 and more points than that, an evenly spaced subset of max_points (in the
  // keyframe's point order) is kept.
  void setKeyframe(const Keyframe& kf, int max_points = 0);
  std::size_t numPoints() const { return p_kf_.size(); }

  // While frames > 0, each successful track() counts per point the event frames in a row whose
  // residual lies beyond `sigmas` robust standard deviations (1.4826 MAD of that solve's residuals);
  // a point with `frames` of them is left out of the solves until the next setKeyframe. Points the
  // reference sees but the camera no longer does (hidden behind a nearer object) disagree with every
  // event frame, while noise does not persist. frames 0: off, the counts cleared and every point back.
  void setPersistentOutliers(int frames, double sigmas);
  // Points left out by that rule: how many, and whether the i-th (setKeyframe's order) is one.
  int numPersistentOutliers() const;
  bool isPersistentOutlier(std::size_t i) const {
    return outlier_frames_ > 0 && strikes_[i] >= outlier_frames_;
  }

  // Refines T_ef_kf and nu (unit 6-vector) from their initial values. If nu is zero, it is
  // initialized by linear least squares given the initial pose.
  // `levels` overrides the configured coarse-to-fine levels (a warm-started frame needs only 1).
  // `prior`, if given, adds a pose prior to the cost.
  TrackResult track(const EventFrame& ef, SE3& T_ef_kf, Vec6& nu, int levels = 0,
                    const PosePrior* prior = nullptr);

  // Remakes the EGM rows for a camera at T_ef_kf (egmRowAtView; track() does it at its start pose when
  // egm_at_view is set); setKeyframe makes them at the keyframe.
  void linearizeAt(const SE3& T_ef_kf);

  // Points of the keyframe that land inside the event frame at T_ef_kf.
  int pointsInView(const SE3& T_ef_kf, int width, int height) const;

  // For tests: residuals r (points in view, in order) and the Jacobian w.r.t. (ξ, ν), where the pose is
  // perturbed as exp(ξ) T_ef_kf and ν additively. Returns the number of points in view.
  int evaluate(const cv::Mat& delta, const SE3& T_ef_kf, const Vec6& nu, Eigen::VectorXd& r,
               Eigen::MatrixXd* J) const;

  // Predicted ΔL̂ (normalized over the points in view) drawn where each point lands in the event
  // frame at T_ef_kf: the model's picture of the event frame, for reports and debug images.
  cv::Mat predictedImage(const SE3& T_ef_kf, const Vec6& nu, int width, int height) const;

  double huberThreshold() const { return huber_; }

 private:
  CameraModel cam_;
  EventTrackerConfig cfg_;
  std::vector<Vec3> p_kf_;   // 3D points in the keyframe
  std::vector<Row6> a_;      // EGM rows
  std::vector<Vec3> g_rho_;  // keyframe log gradient (gx, gy) and inverse depth, for linearizeAt
  std::vector<cv::Point2f> px_kf_;
  // Event frames in a row each point was an outlier in (setPersistentOutliers); saturates at 255.
  std::vector<std::uint8_t> strikes_;
  int outlier_frames_ = 0;
  double outlier_sigmas_ = 0;
  void countStrikes(const Eigen::VectorXd& r, double sigma);
  // One Levenberg-Marquardt solve on one (blurred) event frame; returns the points in view.
  int solveLevel(const cv::Mat& img, SE3& T_ef_kf, Vec6& nu, const PosePrior* prior, Eigen::VectorXd& r,
                 Eigen::MatrixXd& J, double& cost, int& iterations) const;

  // The solve's point set (solve_set_) for a pose: the points that land at least `lo` pixels inside the
  // image; also copies their EGM rows to A_.
  void chooseSet(const SE3& T_ef_kf, double lo, int width, int height) const;
  // Residuals (one per point of the set), their Huber cost and, if J, the Jacobian; returns the number
  // of the set's points inside the image. In fixed chunks of the set, in parallel for large sets.
  int evaluateSet(const cv::Mat& delta, const SE3& T_ef_kf, const Vec6& nu, Eigen::VectorXd& r,
                  Eigen::MatrixXd* J, double huber, double* cost) const;
  // The first pass of a chunk: m, the prediction m̂ and D (if jacobian) per point, and the chunk's sums.
  void measureChunk(int ch, std::size_t b, std::size_t e, const cv::Mat& delta, const Mat3& R, const Vec3& t,
                    const Vec6& nu, bool jacobian) const;
  void normalEquations(const Eigen::VectorXd& r, const Eigen::MatrixXd& J, double huber,
                       Eigen::Matrix<double, 12, 12>& H, Eigen::Matrix<double, 12, 1>& g) const;

  // A chunk's share of the sums that normalize the residuals (Σm², Σm̂², Σ m D, Σ m̂ A), its points inside
  // the image and its Huber cost.
  struct ChunkSums {
    double mm = 0, hh = 0, cost = 0;
    Row6 mD = Row6::Zero(), hA = Row6::Zero();
    int inside = 0;
    void add(const ChunkSums& o) {
      mm += o.mm, hh += o.hh, cost += o.cost, mD += o.mD, hA += o.hA, inside += o.inside;
    }
  };

  double huber_;
  double median_inv_depth_ = 1;  // of the keyframe's points: a step's translation in pixels
  double data_var_;              // variance of one residual (robust, from the last solve): the prior's scale
  mutable cv::Mat blurred_;
  // Scratch (kept between frames: no allocation per frame once warm).
  mutable std::vector<int> solve_set_;   // points of the running solve (see chooseSet)
  mutable std::vector<ChunkSums> sums_;  // one per chunk
  mutable Eigen::VectorXd m_, mh_;
  mutable Eigen::Matrix<double, Eigen::Dynamic, 6> D_, A_;
  // A solve's weights, weighted residuals and weighted Jacobian; the residuals and Jacobian of a step
  // being tried.
  mutable Eigen::VectorXd w_, wr_, r_try_;
  mutable Eigen::MatrixXd J_try_, WJ_;
};

}  // namespace eds
