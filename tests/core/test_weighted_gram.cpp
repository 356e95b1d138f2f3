#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "core/weighted_gram.hpp"

namespace eds {
namespace {

// JᵀWJ and JᵀWr against Eigen's products, for row counts with and without a remainder of four and
// columns of very different scales (a tracker's pose and brightness columns).
TEST(WeightedGram, MatchesTheMatrixProductsOnEveryRowCount) {
  std::mt19937 rng(7);
  std::normal_distribution<double> nd;
  for (const int n : {1, 3, 4, 5, 63, 64, 1001}) {
    Eigen::MatrixXd J(n, 12);
    Eigen::VectorXd w(n), r(n);
    for (int i = 0; i < n; ++i) {
      for (int c = 0; c < 12; ++c) J(i, c) = nd(rng) * (c < 6 ? 100.0 : 0.01);
      w[i] = std::abs(nd(rng)) + 0.1;
      r[i] = nd(rng);
    }
    const Eigen::MatrixXd WJ = w.asDiagonal() * J;
    const Eigen::VectorXd wr = w.cwiseProduct(r);
    const double* cols[12];
    const double* wcols[12];
    for (int c = 0; c < 12; ++c) cols[c] = J.col(c).data(), wcols[c] = WJ.col(c).data();
    Eigen::Matrix<double, 12, 12> H = Eigen::Matrix<double, 12, 12>::Constant(1.0);
    Eigen::Matrix<double, 12, 1> g = Eigen::Matrix<double, 12, 1>::Constant(2.0);
    addWeightedGram<12>(cols, wcols, wr.data(), static_cast<std::size_t>(n), H, g);
    const Eigen::MatrixXd H_ref = (J.transpose() * WJ).array() + 1.0;
    const Eigen::VectorXd g_ref = (J.transpose() * wr).array() + 2.0;
    for (int a = 0; a < 12; ++a) {
      EXPECT_NEAR(g[a], g_ref[a], 1e-12 * (1 + std::abs(g_ref[a]))) << "n " << n << " g " << a;
      for (int b = 0; b < 12; ++b)
        EXPECT_NEAR(H(a, b), H_ref(a, b), 1e-12 * (1 + std::abs(H_ref(a, b))))
            << "n " << n << " H " << a << "," << b;
    }
  }
}

TEST(WeightedGram, FourPartialSumsTakeEveryValueOnce) {
  const std::vector<double> x{1, 2, 3, 4, 5, 6, 7}, y{1, 10, 100, 1000, 1e4, 1e5, 1e6};
  EXPECT_DOUBLE_EQ(dot4(x.data(), y.data(), 7), 7654321.0);
  EXPECT_DOUBLE_EQ(dot4(x.data(), y.data(), 2), 21.0);
  EXPECT_DOUBLE_EQ(dot4(x.data(), y.data(), 0), 0.0);
}

}  // namespace
}  // namespace eds
