// The robust loss and damping schedule the direct solvers share: the weight is the loss's derivative
// over the residual (numerically), the loss is continuous and quadratic inside, and the damping follows
// its schedule down to its floor.
#include <gtest/gtest.h>

#include "core/robust.hpp"

namespace eds {
namespace {

TEST(Robust, HuberWeightIsTheLossDerivativeOverTheResidual) {
  const double k = 0.3, h = 1e-6;
  for (double r : {-2.0, -0.31, -0.2, -1e-3, 0.05, 0.29, 0.31, 1.0, 7.5}) {
    const double derivative = (huberCost(r + h, k) - huberCost(r - h, k)) / (2 * h);
    EXPECT_NEAR(huberWeight(r, k), derivative / r, 1e-6) << r;
  }
  EXPECT_DOUBLE_EQ(huberCost(0.2, 0.3), 0.02);                 // ½r² inside
  EXPECT_DOUBLE_EQ(huberCost(-1.0, 0.3), 0.3 * (1.0 - 0.15));  // linear beyond
  EXPECT_NEAR(huberCost(0.3 - 1e-12, 0.3), huberCost(0.3 + 1e-12, 0.3), 1e-11);
  EXPECT_DOUBLE_EQ(huberWeight(0.0, 0.3), 1.0);
}

TEST(Robust, DampingGrowsOnRejectionAndShrinksToItsFloor) {
  LmDamping lm(1e-3, 1e-5);
  lm.rejected();
  EXPECT_DOUBLE_EQ(lm.lambda(), 1e-2);
  lm.accepted();
  EXPECT_DOUBLE_EQ(lm.lambda(), 1e-2 * 0.3);
  for (int i = 0; i < 20; ++i) lm.accepted();
  EXPECT_DOUBLE_EQ(lm.lambda(), 1e-5);
}

}  // namespace
}  // namespace eds
