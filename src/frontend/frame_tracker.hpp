#pragma once
// FrameTracker: direct photometric alignment of a frame to a keyframe with known depth (DSO-style):
// minimizes the Huber norm of I_f(π(T p)) − (α I_kf(u) + β) over T_f_kf and the affine brightness
// (α, β), over DSO's 8-pixel pattern around each keyframe point, coarse-to-fine on an image pyramid,
// from a given initial pose (the event tracker's, in EDS). Analytic Jacobians (checked by a test).
#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.hpp"
#include "core/parallel.hpp"
#include "core/reflect.hpp"
#include "core/se3.hpp"
#include "map/keyframe.hpp"

namespace eds {

struct FrameTrackerConfig {
  int levels = 3;            // pyramid levels (each half the size of the previous)
  int max_iterations = 15;   // per level
  double huber = 9.0 / 255;  // intensity units (DSO: 9 gray levels)
  bool affine = true;        // estimate α, β (off: brightness constancy)
  double max_rmse = 0.08;    // above this at the finest level: reported as lost
  int min_residuals = 100;
  double convergence = 1e-8;  // a level ends when the cost falls by less than this fraction
  // A level also ends when a rejected step was shorter than this (radians and map units; the map's
  // median depth is ~1): at the minimum the steps are ~1e-6, and retrying them with more damping
  // (up to 5 evaluations) changes nothing. 0: off.
  double min_step = 0;
  // A fit whose gain α ends below this is reported as lost: a tenfold darkening leaves little of the
  // scene, and such fits matched the frame to a flat or inverted keyframe. Must be > 0.
  double min_gain = 0.1;
};

EDS_FIELDS(FrameTrackerConfig, levels, max_iterations, huber, affine, max_rmse, min_residuals, convergence,
           min_step, min_gain)

struct FrameTrackResult {
  bool ok = false;
  double rmse = 0;    // robust residual RMSE at the finest level, intensity units
  int residuals = 0;  // in view at the finest level
  int iterations = 0;
  int evaluations = 0;  // residual evaluations over all levels: what the alignment cost
};

class FrameTracker {
 public:
  FrameTracker(const CameraModel& pinhole, FrameTrackerConfig cfg);
  // Keyframe image pyramid and 3D points of its points with depth.
  void setKeyframe(const Keyframe& kf);
  // Refines T_f_kf (frame from keyframe) and α, β, from their initial values. `frame` is the
  // undistorted image, CV_32F in [0, 1]; NaN marks pixels that hold no information (clipped), whose
  // residuals are left out.
  // levels > 0: start at that many levels from the finest (a good initial pose, e.g. the event
  // tracker's, needs no coarse levels); 0: all.
  FrameTrackResult track(const cv::Mat& frame, SE3& T_f_kf, double& alpha, double& beta,
                         int levels = 0) const;

  // For tests: residuals and Jacobian (columns ξ (6), α, β) at pyramid level `level`.
  // The image derivative is that of the bilinear interpolant itself, so the Jacobian is exact.
  int evaluate(int level, const cv::Mat& frame_level, const SE3& T_f_kf, double alpha, double beta,
               std::vector<double>& r, std::vector<Eigen::Matrix<double, 1, 8>>* J) const;
  // Builds the image pyramid of a frame (exposed for tests).
  void pyramid(const cv::Mat& frame, std::vector<cv::Mat>& img) const;

 private:
  // A level's keyframe points (pattern pixels) as arrays: the projection runs over them in vector
  // instructions.
  struct LevelPoints {
    std::vector<double> x, y, z;  // 3D point in the keyframe
    std::vector<float> ref;       // keyframe intensity at the pixel
  };
  // One evaluation: residuals and Jacobian columns (ξ (6), α, β) of the points in view, and the
  // per-point values the Jacobian is built from (kept between the evaluations of one alignment). The
  // points go in fixed chunks; chunk k's residuals are at [first[k], first[k] + count[k]), with the
  // sums of their Huber costs and clipped squares.
  struct Evaluation {
    std::vector<double> r;
    std::array<std::vector<double>, 8> J;
    std::vector<double> u, v, qx, qy, qz, iz, dx, dy, ref;
    std::array<std::size_t, kReductionChunks> first{}, count{};
    std::array<double, kReductionChunks> cost{}, ss{};
  };
  CameraModel levelCamera(int level) const;
  int evaluate(int level, const cv::Mat& img, const SE3& T, double alpha, double beta, Evaluation& e,
               bool jacobian) const;
  void normalEquations(const Evaluation& e, Eigen::Matrix<double, 8, 8>& H,
                       Eigen::Matrix<double, 8, 1>& g) const;

  CameraModel cam_;
  FrameTrackerConfig cfg_;
  std::vector<LevelPoints> points_;  // per level
};

// The camera of pyramid level `level` (each level half the size of the one below; pixel centres at
// integers on every level: x_l = (x + 0.5) / 2^l - 0.5).
CameraModel pyramidCamera(const CameraModel& cam, int level);

}  // namespace eds
