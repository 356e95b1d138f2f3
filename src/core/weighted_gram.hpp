#pragma once
// The normal equations JᵀWJ and JᵀWr of a tracker's few columns over many residuals. A general matrix
// product packs both operands and forms all N² entries; here each of the N(N+1)/2 distinct entries is a
// dot product over contiguous columns in four fixed partial sums, so the compiler vectorizes it and the
// result is the same on any vector width.
#include <Eigen/Core>
#include <algorithm>
#include <cstddef>

namespace eds {

// Σ x_i y_i over n values in four interleaved partial sums (the remainder in the first).
inline double dot4(const double* x, const double* y, std::size_t n) {
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4)
    s0 += x[i] * y[i], s1 += x[i + 1] * y[i + 1], s2 += x[i + 2] * y[i + 2], s3 += x[i + 3] * y[i + 3];
  for (; i < n; ++i) s0 += x[i] * y[i];
  return (s0 + s2) + (s1 + s3);
}

// Adds the upper triangle of Σ_b wcol_a · col_b and Σ_a col_a · wr over n rows to H and g, then
// mirrors H. col[a]: column a of J; wcol[a]: the same column times the weights; wr: weights times r.
template <int N>
void addWeightedGram(const double* const* col, const double* const* wcol, const double* wr, std::size_t n,
                     Eigen::Matrix<double, N, N>& H, Eigen::Matrix<double, N, 1>& g) {
  for (int a = 0; a < N; ++a) {
    for (int b = a; b < N; ++b) H(a, b) += dot4(wcol[a], col[b], n);
    g[a] += dot4(col[a], wr, n);
  }
  for (int a = 0; a < N; ++a)
    for (int b = a + 1; b < N; ++b) H(b, a) = H(a, b);
}

}  // namespace eds
