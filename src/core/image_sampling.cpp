#include "core/image_sampling.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace eds {

namespace {
// Catmull-Rom weights and their derivatives for fraction t in [0, 1).
inline void cubicWeights(double t, double w[4], double dw[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t);
  w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
  dw[0] = 0.5 * (-3 * t2 + 4 * t - 1);
  dw[1] = 0.5 * (9 * t2 - 10 * t);
  dw[2] = 0.5 * (-9 * t2 + 8 * t + 1);
  dw[3] = 0.5 * (3 * t2 - 2 * t);
}
}  // namespace

double sampleBicubic(const cv::Mat& img, double x, double y, double* dx, double* dy) {
  const int W = img.cols, H = img.rows;
  const double fx = std::floor(x), fy = std::floor(y);
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  // Double accumulation: the tracker's numeric Jacobian checks need more than float's 7 digits.
  double wx[4], dwx[4], wy[4], dwy[4];
  cubicWeights(x - fx, wx, dwx);
  cubicWeights(y - fy, wy, dwy);
  // The four rows are combined first (weights in y), each row as four doubles: one AVX register where
  // the build has it; then the weights in x. Away from the border (nearly every call) the rows are read
  // without clamping.
  const bool interior = x0 >= 1 && y0 >= 1 && x0 + 2 < W && y0 + 2 < H;
  Eigen::Array4d col_v = Eigen::Array4d::Zero(), col_d = Eigen::Array4d::Zero();
  for (int j = 0; j < 4; ++j) {
    Eigen::Array4f row;
    if (interior) {
      row = Eigen::Map<const Eigen::Array4f>(img.ptr<float>(y0 - 1 + j) + (x0 - 1));
    } else {
      const float* r = img.ptr<float>(std::clamp(y0 - 1 + j, 0, H - 1));
      for (int i = 0; i < 4; ++i) row[i] = r[std::clamp(x0 - 1 + i, 0, W - 1)];
    }
    const Eigen::Array4d p = row.cast<double>();
    col_v += wy[j] * p;
    col_d += dwy[j] * p;
  }
  const Eigen::Map<const Eigen::Array4d> Wx(wx), dWx(dwx);
  const double val = (Wx * col_v).sum(), gx = (dWx * col_v).sum(), gy = (Wx * col_d).sum();
  if (dx) *dx = gx;
  if (dy) *dy = gy;
  return val;
}

}  // namespace eds
