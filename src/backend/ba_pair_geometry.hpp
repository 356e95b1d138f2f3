#pragma once
// The photometric bundle adjustment's geometry of a (host, target) frame pair: the relative poses of
// every pair, and one (point, target) pair's residual Jacobian over DSO's eight-pixel pattern, the
// eight pixels at once as arrays (vector instructions). Used by photometric_ba.cpp only.
#include <Eigen/Core>
#include <vector>

#include "backend/photometric_ba.hpp"
#include "core/camera.hpp"
#include "core/se3.hpp"

namespace eds {

// DSO's residual pattern as offset arrays (pixels), and an array over its eight pixels.
inline constexpr double kPatternU[8] = {0, -1, 1, -2, 0, 2, -1, 0};
inline constexpr double kPatternV[8] = {-2, -1, -1, 0, 0, 0, 1, 2};
using Arr8 = Eigen::Array<double, 8, 1>;

// Relative pose of every (host, target) pair and what the residual needs of it, computed once per
// state instead of once per point.
struct PairTransforms {
  int F = 0;
  std::vector<SE3> T_t_h;
  std::vector<Mat3> R_t_h, R_t_w;
  std::vector<double> e;    // e^{a_t − a_h}
  std::vector<Mat3> R_w_c;  // per frame
  std::vector<Vec3> t_w_c;
  explicit PairTransforms(const std::vector<BaFrame>& frames);
};

// One (point, target) pair's Jacobian, compactly: the host's columns are [A, e] and the target's [-A, -1]
// (A: pose and a_h, e = e^{a_t − a_h} on every row; the brightness offsets enter linearly), then the
// inverse depth's.
struct PairJacobian {
  Eigen::Matrix<double, 8, 7> A;
  double e = 1;
  Eigen::Matrix<double, 8, 1> d_rho;
};

// The frames as their Jacobians are evaluated (DSO's first-estimate Jacobians): frames the prior holds
// at the prior's linearization point, the others at the current state.
struct LinearizationState {
  const std::vector<BaFrame>* frames = nullptr;
  const PairTransforms* pairs = nullptr;
};

// What evaluateCore computed per pattern pixel that its Jacobian needs.
struct PatternGeometry {
  const Arr8* RX;  // R_t_h x_h (3 arrays)
  const Arr8* X;   // the point in the target (3 arrays)
  const Arr8 &iz, &I_h, &dx, &dy;
};

// The Jacobian of evaluateCore's residuals. First-estimate Jacobians (lin): the geometry (projection,
// frame poses, brightness) at the frames' linearization points; only the image gradient is taken at the
// current projection.
void pairJacobian(const CameraModel& cam, const std::vector<BaFrame>& frames, const PairTransforms& pairs,
                  int host, int target, const Vec3& x_c, double inv_rho, const PatternGeometry& pg,
                  PairJacobian& J, const LinearizationState* lin);

}  // namespace eds
