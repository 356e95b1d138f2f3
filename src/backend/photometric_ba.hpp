#pragma once
// Photometric bundle adjustment (paper §3.3, DSO's formulation): keyframe poses T_w_c, affine brightness
// (a, b) per keyframe, and one inverse depth per point, minimizing over every point, every keyframe it
// is seen in, and DSO's 8-pixel pattern around it
//     r = I_t(π(T_t_h π⁻¹(u_k, ρ))) − b_t − e^{a_t − a_h} (I_h(u_k) − b_h)
// with the Huber norm and a gradient-dependent weight c² / (c² + |∇I_h|²). Gauss-Newton with
// Levenberg damping; the points are eliminated by the Schur complement (each has one parameter), so a
// step costs O(residuals) plus a dense solve of 8 parameters per keyframe. The residuals are evaluated
// and accumulated on all cores (TBB), in a fixed split of the points whose partial sums are added in
// order, so that results do not depend on the thread count (ESIM, 2 cores: 101 -> 50 ms per keyframe).
//
// Gauge: frames marked `fixed` are held (the window holds its oldest keyframe). Information of
// keyframes and points that leave the window can be kept as a Gaussian prior (BaPrior, from
// marginalize()). With DSO's first-estimate Jacobians: once a frame is in the prior, every Jacobian
// that involves it is taken at the prior's linearization point of it (residuals and image gradients
// at the current state), and the prior is never relinearized. Otherwise the prior, combined with
// residuals linearized elsewhere, gains information along the gauge (the monocular scale) and pulls it.
#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.hpp"
#include "core/reflect.hpp"
#include "core/se3.hpp"

namespace eds {

struct BaConfig {
  int iterations = 6;
  double huber = 9.0 / 255.0;  // intensity units
  double grad_weight_c = 50.0 / 255.0;
  double outlier_energy = 0.08;  // per-pattern RMS above this (after the solve): observation dropped
  double lambda_initial = 1e-4;
};

EDS_FIELDS(BaConfig, iterations, huber, grad_weight_c, outlier_energy, lambda_initial)

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
  // Optional Gaussian prior on the inverse depth, ½ w (ρ − ρ0)²: the bootstrap uses it while the
  // baseline is too short for depth to be observable.
  double prior_weight = 0, prior_inv_depth = 1.0;
};

// A Gaussian prior over some frames' parameters, E(x) = bᵀx + ½ xᵀHx with, per frame, the 8-vector
// x = (log(T_w_c · T0⁻¹), a − a0, b − b0) (the same left perturbation as the solve).
struct BaPrior {
  std::vector<int> frames;  // indices into the frame vector
  std::vector<SE3> T0;
  std::vector<double> a0, b0;
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  bool empty() const { return frames.empty(); }
  // x of every prior frame, stacked.
  Eigen::VectorXd delta(const std::vector<BaFrame>& frames_now) const;
  double energy(const std::vector<BaFrame>& frames_now) const;
  // Re-indexes after frame `removed` was erased from the frame vector (indices above it shift down).
  void eraseFrameIndex(int removed);
};

struct BaStats {
  int iterations = 0;
  double initial_rmse = 0, final_rmse = 0;  // over inlier residuals, intensity units
  double initial_cost = 0;  // the energy minimized (weighted Huber norm, prior included) at the start
  int residuals = 0;
  int outliers_removed = 0;
};

struct NormalEquations;     // defined in photometric_ba.cpp
struct CostSums;            // defined in photometric_ba.cpp
struct PairTransforms;      // defined in ba_pair_geometry.hpp
struct LinearizationState;  // defined in ba_pair_geometry.hpp
struct PairJacobian;        // defined in ba_pair_geometry.hpp

// Per point: the gradient weight c²/(c²+|∇I|²) and the host intensity of each pattern pixel (both
// constant during a solve).
struct HostPattern {
  std::array<double, 8> w{}, I{};
};

class PhotometricBA {
 public:
  PhotometricBA(const CameraModel& pinhole, BaConfig cfg);
  BaStats optimize(std::vector<BaFrame>& frames, std::vector<BaPoint>& points,
                   const BaPrior* prior = nullptr) const;

  // Marginalizes frame m: the residuals of the points hosted in m (linearized at the current state,
  // points eliminated by the Schur complement) and the existing prior become a prior over every other
  // frame. The caller then erases frame m, its points and the observations of other points in m
  // (those are dropped, as DSO does), and calls prior.eraseFrameIndex(m).
  BaPrior marginalize(const std::vector<BaFrame>& frames, const std::vector<BaPoint>& points,
                      const BaPrior* prior, int m) const;

  // For tests: the 8 pattern residuals of point p in target t and their Jacobians with respect to
  // (host pose ξ_h (6), host a, b, target pose ξ_t (6), target a, b, inverse depth): 8 x 17.
  // Poses are perturbed on the left in the world frame: T_w_c <- exp(ξ) T_w_c. Returns false if any
  // pattern pixel leaves the target image.
  bool evaluate(const std::vector<BaFrame>& frames, const BaPoint& p, int target,
                Eigen::Matrix<double, 8, 1>& r, Eigen::Matrix<double, 8, 17>* J) const;

  // Each point's RMS pattern residual in frame `target` (√(|r|²/8) of evaluate()), NaN where the point
  // is hosted there or its pattern leaves the image: the frames' pair transforms are built once.
  std::vector<double> patternRms(const std::vector<BaFrame>& frames, const std::vector<BaPoint>& points,
                                 int target) const;

  // For tests: the normal equations JᵀWJ and JᵀWr the solve builds, dense over every frame (8
  // parameters each, fixed or not, in order) and then every point's inverse depth.
  void denseNormalEquations(const std::vector<BaFrame>& frames, const std::vector<BaPoint>& points,
                            Eigen::MatrixXd& H, Eigen::VectorXd& b) const;

 private:
  // The residuals of one point in one target at inverse depth rho (evaluate() without the point).
  // host_values: the 8 host intensities (HostPattern::I), or null to sample them.
  bool evaluateCore(const std::vector<BaFrame>& frames, const PairTransforms& pairs, int host, float u,
                    float v, double rho, int target, Eigen::Matrix<double, 8, 1>& r, PairJacobian* J,
                    const double* host_values = nullptr, const LinearizationState* lin = nullptr) const;
  std::vector<HostPattern> hostPatterns(const std::vector<BaFrame>& frames,
                                        const std::vector<BaPoint>& points) const;
  double cost(const std::vector<BaFrame>& frames, const std::vector<BaPoint>& points,
              const std::vector<double>& rho, const std::vector<HostPattern>& gw, const BaPrior* prior,
              double* rmse, int* count) const;
  // Accumulates the normal equations of the photometric terms (and point priors); frames with
  // slot < 0 are constant. only_host >= 0: only the points hosted in that frame. Jacobians of the
  // frames `prior` holds are taken at its linearization point. sums: also the cost of these terms,
  // as cost() adds it, from the same residuals.
  void accumulate(const std::vector<BaFrame>& frames, const std::vector<BaPoint>& points,
                  const std::vector<double>& rho, const std::vector<HostPattern>& gw,
                  const std::vector<int>& slot, int dim, NormalEquations& ne, const BaPrior* prior,
                  int only_host = -1, CostSums* sums = nullptr) const;

  struct StepScratch {  // reused across the damped steps of one optimize()
    Eigen::MatrixXd S;
    Eigen::VectorXd s;
    std::vector<double> hpp_d;
    Eigen::MatrixXd U;  // the point columns of Hfp, each scaled by 1/√(damped Hpp)
    Eigen::VectorXd v;  // bp / damped Hpp
  };
  void addPrior(const BaPrior& prior, const std::vector<BaFrame>& frames, const std::vector<int>& slot,
                NormalEquations& ne) const;
  bool dampedStep(const NormalEquations& ne, double lambda, int dim, const std::vector<double>& rho,
                  StepScratch& w, Eigen::VectorXd& df, std::vector<double>& rho_new) const;
  int removeOutliers(const std::vector<BaFrame>& frames, std::vector<BaPoint>& points,
                     const std::vector<HostPattern>& gw, double* rmse, int* count) const;

  CameraModel cam_;
  BaConfig cfg_;
};

}  // namespace eds
