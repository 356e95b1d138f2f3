#pragma once
// Photometric bundle adjustment (paper §3.3, DSO's formulation): keyframe poses T_w_c, affine brightness
// (a, b) per keyframe, and one inverse depth per point, minimizing over every point, every keyframe it
// is seen in, and DSO's 8-pixel pattern around it
//     r = I_t(π(T_t_h π⁻¹(u_k, ρ))) − b_t − e^{a_t − a_h} (I_h(u_k) − b_h)
// with the Huber norm and a gradient-dependent weight c² / (c² + |∇I_h|²). Gauss-Newton with
// Levenberg damping; the points are eliminated by the Schur complement (each has one parameter), so a
// step costs O(residuals) plus a dense solve of 8 parameters per keyframe.
//
// Gauge: the first keyframe (pose and brightness) is held fixed; monocular scale is left to the
// damping and to the caller (a marginalization prior is the next step, see issue #5).
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.hpp"
#include "core/se3.hpp"

namespace eds {

struct BaConfig {
  int iterations = 6;
  double huber = 9.0 / 255.0;  // intensity units
  double grad_weight_c = 50.0 / 255.0;
  double outlier_energy = 0.08;  // per-pattern RMS above this (after the solve): observation dropped
  double lambda_initial = 1e-4;
};

struct BaFrame {
  SE3 T_w_c;
  double a = 0, b = 0;  // affine brightness: I ≈ e^{-a} (I_true) + b, DSO convention
  cv::Mat image;        // CV_32F in [0, 1], undistorted
  bool fixed = false;
};

struct BaPoint {
  int host = 0;
  float u = 0, v = 0;  // pixel in the host frame
  double inv_depth = 1.0;
  std::vector<int> targets;  // frames it is observed in (not the host)
  bool outlier = false;
};

struct BaStats {
  int iterations = 0;
  double initial_rmse = 0, final_rmse = 0;  // over inlier residuals, intensity units
  int residuals = 0;
  int outliers_removed = 0;
};

class PhotometricBA {
 public:
  PhotometricBA(const CameraModel& pinhole, BaConfig cfg);
  BaStats optimize(std::vector<BaFrame>& frames, std::vector<BaPoint>& points) const;

  // For tests: the 8 pattern residuals of point p in target t and their Jacobians with respect to
  // (host pose ξ_h (6), host a, b, target pose ξ_t (6), target a, b, inverse depth): 8 x 17.
  // Poses are perturbed on the left in the world frame: T_w_c <- exp(ξ) T_w_c. Returns false if any
  // pattern pixel leaves the target image.
  bool evaluate(const std::vector<BaFrame>& frames, const BaPoint& p, int target,
                Eigen::Matrix<double, 8, 1>& r, Eigen::Matrix<double, 8, 17>* J) const;

 private:
  CameraModel cam_;
  BaConfig cfg_;
};

}  // namespace eds
