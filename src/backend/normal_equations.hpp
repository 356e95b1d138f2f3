#pragma once
// The photometric bundle adjustment's normal equations, shared by its solve and its marginalization.
#include <Eigen/Core>
#include <vector>

namespace eds {

inline constexpr int kFrameParams = 8;  // per keyframe: pose (6), a, b

// Normal equations of the photometric terms with the points kept apart (one inverse depth each), so
// that they can be eliminated by the Schur complement. Hfp holds one column per point.
struct NormalEquations {
  Eigen::MatrixXd Hff;
  Eigen::VectorXd bf;
  std::vector<double> Hpp, bp;
  Eigen::MatrixXd Hfp;
};

}  // namespace eds
