#pragma once
// The robust loss and the damping schedule shared by the direct solvers (frame tracker, event tracker,
// photometric bundle adjustment), so that they cannot drift apart.
#include <algorithm>
#include <cmath>

namespace eds {

// Huber's loss: ½r² for |r| <= k, k(|r| − ½k) beyond.
inline double huberCost(double r, double k) {
  const double a = std::abs(r);
  return a <= k ? 0.5 * a * a : k * (a - 0.5 * k);
}

// Its iteratively-reweighted-least-squares weight ρ'(r)/r: 1 for |r| <= k, k/|r| beyond.
inline double huberWeight(double r, double k) {
  const double a = std::abs(r);
  return a <= k ? 1.0 : k / a;
}

// Levenberg-Marquardt damping λ: ten times larger after a rejected step, 0.3 times after an accepted
// one, never below `floor` (a solver whose steps stay good settles to near Gauss-Newton).
class LmDamping {
 public:
  static constexpr double kRejectFactor = 10.0;
  static constexpr double kAcceptFactor = 0.3;
  LmDamping(double initial, double floor) : lambda_(initial), floor_(floor) {}
  double lambda() const { return lambda_; }
  void accepted() { lambda_ = std::max(floor_, lambda_ * kAcceptFactor); }
  void rejected() { lambda_ *= kRejectFactor; }

 private:
  double lambda_, floor_;
};

}  // namespace eds
