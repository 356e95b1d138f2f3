#include "frontend/frame_tracker.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "core/image_sampling.hpp"
#include "core/parallel.hpp"
#include "core/robust.hpp"
#include "core/weighted_gram.hpp"

namespace eds {

namespace {

// Damping of each pyramid level's solve (core/robust.hpp's schedule).
constexpr double kLambdaInitial = 1e-3, kLambdaFloor = 1e-6;
// DSO's residual pattern #8.
constexpr int kPattern[8][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0}, {0, 0}, {2, 0}, {-1, 1}, {0, 2}};

// JᵀWJ and JᵀWr of n residuals with the Huber weights of r, from the Jacobian's columns: they go
// through in blocks that fit the first-level cache, each weighted for core/weighted_gram.hpp.
void normalEquations(const double* const* J, const double* r, std::size_t n, double huber,
                     Eigen::Matrix<double, 8, 8>& H, Eigen::Matrix<double, 8, 1>& g) {
  constexpr std::size_t kBlock = 64;
  alignas(32) double wcol[8][kBlock], wr[kBlock], w[kBlock];
  const double* cols[8];
  const double* wcols[8];
  for (int c = 0; c < 8; ++c) wcols[c] = wcol[c];
  H.setZero(), g.setZero();
  for (std::size_t b0 = 0; b0 < n; b0 += kBlock) {
    const std::size_t m = std::min(kBlock, n - b0);
    for (std::size_t i = 0; i < m; ++i) w[i] = huberWeight(r[b0 + i], huber), wr[i] = w[i] * r[b0 + i];
    for (int c = 0; c < 8; ++c) {
      cols[c] = J[c] + b0;
      for (std::size_t i = 0; i < m; ++i) wcol[c][i] = w[i] * cols[c][i];
    }
    addWeightedGram<8>(cols, wcols, wr, m, H, g);
  }
}

// The points' projection, as plain loops over unaliased arrays (__restrict parameters) that the
// compiler vectorizes.
void project(const Mat3& R, const Vec3& t, const CameraModel& c, const double* __restrict x,
             const double* __restrict y, const double* __restrict z, std::size_t n, double* __restrict qx,
             double* __restrict qy, double* __restrict qz, double* __restrict iz, double* __restrict u,
             double* __restrict v) {
  const double r00 = R(0, 0), r01 = R(0, 1), r02 = R(0, 2), r10 = R(1, 0), r11 = R(1, 1), r12 = R(1, 2);
  const double r20 = R(2, 0), r21 = R(2, 1), r22 = R(2, 2), tx = t.x(), ty = t.y(), tz = t.z();
  const double fx = c.fx, fy = c.fy, cx = c.cx, cy = c.cy;
  for (std::size_t i = 0; i < n; ++i) {
    qx[i] = r00 * x[i] + r01 * y[i] + r02 * z[i] + tx;
    qy[i] = r10 * x[i] + r11 * y[i] + r12 * z[i] + ty;
    qz[i] = r20 * x[i] + r21 * y[i] + r22 * z[i] + tz;
    iz[i] = 1.0 / qz[i];
    u[i] = fx * qx[i] * iz[i] + cx, v[i] = fy * qy[i] * iz[i] + cy;
  }
}

// The Jacobian columns (ξ (6), α, β) of m residuals from their points and image gradients.
void jacobianColumns(const CameraModel& c, const double* __restrict qx, const double* __restrict qy,
                     const double* __restrict qz, const double* __restrict iz, const double* __restrict dx,
                     const double* __restrict dy, const double* __restrict ref, std::size_t m,
                     double* __restrict J0, double* __restrict J1, double* __restrict J2,
                     double* __restrict J3, double* __restrict J4, double* __restrict J5,
                     double* __restrict J6, double* __restrict J7) {
  const double fx = c.fx, fy = c.fy;
  for (std::size_t i = 0; i < m; ++i) {
    const double gx = dx[i] * fx * iz[i], gy = dy[i] * fy * iz[i];
    const double gz = -(dx[i] * fx * qx[i] + dy[i] * fy * qy[i]) * iz[i] * iz[i];
    J0[i] = gx, J1[i] = gy, J2[i] = gz;
    J3[i] = qy[i] * gz - qz[i] * gy, J4[i] = qz[i] * gx - qx[i] * gz, J5[i] = qx[i] * gy - qy[i] * gx;
    J6[i] = -ref[i], J7[i] = -1.0;
  }
}

// Below this many points a level's evaluation costs more to hand out to threads than to do.
constexpr std::size_t kParallelPoints = 4000;
}  // namespace

FrameTracker::FrameTracker(const CameraModel& pinhole, FrameTrackerConfig cfg) : cam_(pinhole), cfg_(cfg) {
  if (cfg_.levels < 1 || cfg_.levels > 6) throw std::invalid_argument("frame tracker: levels must be 1..6");
  if (!(cfg_.huber > 0)) throw std::invalid_argument("frame tracker: huber must be > 0");
}

CameraModel pyramidCamera(const CameraModel& cam, int level) {
  const double s = 1.0 / (1 << level);
  CameraModel c = cam;
  c.fx *= s, c.fy *= s;
  c.cx = (cam.cx + 0.5) * s - 0.5;
  c.cy = (cam.cy + 0.5) * s - 0.5;
  c.width = cam.width >> level, c.height = cam.height >> level;
  return c;
}

CameraModel FrameTracker::levelCamera(int level) const { return pyramidCamera(cam_, level); }

void FrameTracker::pyramid(const cv::Mat& frame, std::vector<cv::Mat>& img) const {
  img.resize(cfg_.levels);
  img[0] = frame;
  for (int l = 1; l < cfg_.levels; ++l)
    cv::resize(img[l - 1], img[l], cv::Size(img[l - 1].cols / 2, img[l - 1].rows / 2), 0, 0, cv::INTER_AREA);
}

void FrameTracker::setKeyframe(const Keyframe& kf) {
  std::vector<cv::Mat> img;
  pyramid(kf.image, img);
  points_.assign(cfg_.levels, LevelPoints{});
  for (int l = 0; l < cfg_.levels; ++l) {
    const CameraModel c = levelCamera(l);
    const double s = 1.0 / (1 << l);
    for (const KeyframePoint& p : kf.points) {
      if (!(p.inv_depth > 0)) continue;
      const double ul = (p.u + 0.5) * s - 0.5, vl = (p.v + 0.5) * s - 0.5;
      // Coarse levels: one residual per point (the pattern would span several fine pixels' worth).
      const int npat = l == 0 ? 8 : 1;
      for (int k = 0; k < npat; ++k) {
        const double u = ul + (npat == 8 ? kPattern[k][0] : 0), v = vl + (npat == 8 ? kPattern[k][1] : 0);
        if (u < 0 || v < 0 || u >= c.width - 1 || v >= c.height - 1) continue;
        const Vec3 p_kf = c.pinholeRay(u, v) * (1.0 / p.inv_depth);
        LevelPoints& P = points_[l];
        P.x.push_back(p_kf.x()), P.y.push_back(p_kf.y()), P.z.push_back(p_kf.z());
        P.ref.push_back(sampleBilinear(img[l], u, v));
      }
    }
  }
  if (points_[0].x.empty()) throw std::invalid_argument("frame tracker: keyframe has no point with depth");
}

int FrameTracker::evaluate(int level, const cv::Mat& img, const SE3& T, double alpha, double beta,
                           std::vector<double>& r, std::vector<Eigen::Matrix<double, 1, 8>>* J) const {
  Evaluation e;
  evaluate(level, img, T, alpha, beta, e, J != nullptr);
  r.clear();
  if (J) J->clear();
  for (int ch = 0; ch < kReductionChunks; ++ch) {
    for (std::size_t i = e.first[ch]; i < e.first[ch] + e.count[ch]; ++i) {
      r.push_back(e.r[i]);
      if (!J) continue;
      Eigen::Matrix<double, 1, 8> row;
      for (int c = 0; c < 8; ++c) row[c] = e.J[c][i];
      J->push_back(row);
    }
  }
  return static_cast<int>(r.size());
}

// In fixed chunks of the points (in parallel when there are many; the sums are the same either way),
// three passes each: the projection of every point (vector instructions), the image samples of those
// in view (gathered, compacted to the chunk's front), then the Jacobian columns of those.
int FrameTracker::evaluate(int level, const cv::Mat& img, const SE3& T, double alpha, double beta,
                           Evaluation& e, bool jacobian) const {
  const CameraModel c = levelCamera(level);
  const Mat3 R = T.rotationMatrix();
  const Vec3 t = T.translation();
  const LevelPoints& P = points_[level];
  const std::size_t n = P.x.size();
  for (auto* a : {&e.r, &e.u, &e.v, &e.qx, &e.qy, &e.qz, &e.iz, &e.dx, &e.dy, &e.ref}) a->resize(n);
  if (jacobian)
    for (auto& col : e.J) col.resize(n);
  const double huber = cfg_.huber;
  forEachChunk(
      n,
      [&](int ch, std::size_t b, std::size_t end) {
        // Pointers by arithmetic on data(): a chunk may be empty, and then b may be the array's end.
        const auto at = [b](auto& a) { return a.data() + b; };
        project(R, t, c, at(P.x), at(P.y), at(P.z), end - b, at(e.qx), at(e.qy), at(e.qz), at(e.iz), at(e.u),
                at(e.v));
        std::size_t m = b;  // in view: compacted in place (m <= i)
        double cost = 0, ss = 0;
        for (std::size_t i = b; i < end; ++i) {
          const double u = e.u[i], v = e.v[i];
          if (e.qz[i] <= 1e-6 || !(u >= 1 && v >= 1 && u < c.width - 2 && v < c.height - 2)) continue;
          double dx, dy;
          const double I = sampleBilinear(img, u, v, dx, dy);
          if (!std::isfinite(I)) continue;  // a pixel marked as holding no information (clipped)
          const double r = I - (alpha * P.ref[i] + beta);
          e.r[m] = r;
          cost += huberCost(r, huber), ss += std::min(r * r, huber * huber);
          e.qx[m] = e.qx[i], e.qy[m] = e.qy[i], e.qz[m] = e.qz[i], e.iz[m] = e.iz[i];
          e.dx[m] = dx, e.dy[m] = dy, e.ref[m] = P.ref[i];
          ++m;
        }
        e.first[ch] = b, e.count[ch] = m - b, e.cost[ch] = cost, e.ss[ch] = ss;
        if (jacobian)
          jacobianColumns(c, at(e.qx), at(e.qy), at(e.qz), at(e.iz), at(e.dx), at(e.dy), at(e.ref), m - b,
                          at(e.J[0]), at(e.J[1]), at(e.J[2]), at(e.J[3]), at(e.J[4]), at(e.J[5]), at(e.J[6]),
                          at(e.J[7]));
      },
      n >= kParallelPoints);
  std::size_t total = 0;
  for (std::size_t k : e.count) total += k;
  return static_cast<int>(total);
}

// The normal equations of an evaluation, per chunk (in parallel like the evaluation), summed in order.
void FrameTracker::normalEquations(const Evaluation& e, Eigen::Matrix<double, 8, 8>& H,
                                   Eigen::Matrix<double, 8, 1>& g) const {
  std::array<Eigen::Matrix<double, 8, 8>, kReductionChunks> Hc;
  std::array<Eigen::Matrix<double, 8, 1>, kReductionChunks> gc;
  const auto body = [&](int ch) {
    const std::size_t b = e.first[ch];
    const double* J[8];
    for (int c = 0; c < 8; ++c) J[c] = e.J[c].data() + b;
    ::eds::normalEquations(J, e.r.data() + b, e.count[ch], cfg_.huber, Hc[ch], gc[ch]);
  };
  forEachChunkIndex(body, e.r.size() >= kParallelPoints);
  H.setZero(), g.setZero();
  for (int ch = 0; ch < kReductionChunks; ++ch) H += Hc[ch], g += gc[ch];
}

FrameTrackResult FrameTracker::track(const cv::Mat& frame, SE3& T, double& alpha, double& beta,
                                     int levels) const {
  if (points_.empty()) throw std::logic_error("FrameTracker::track before setKeyframe");
  std::vector<cv::Mat> img;
  pyramid(frame, img);
  FrameTrackResult res;
  Evaluation e, e_new;
  const int np = cfg_.affine ? 8 : 6;
  const auto cost = [](const Evaluation& ev) {  // mean: the point count changes with the pose
    double c = 0;
    std::size_t n = 0;
    for (int ch = 0; ch < kReductionChunks; ++ch) c += ev.cost[ch], n += ev.count[ch];
    return c / std::max<std::size_t>(1, n);
  };
  Eigen::Matrix<double, 8, 8> H;
  Eigen::Matrix<double, 8, 1> g;
  const int start = levels > 0 ? std::min(levels, cfg_.levels) - 1 : cfg_.levels - 1;
  for (int l = start; l >= 0; --l) {
    LmDamping lm(kLambdaInitial, kLambdaFloor);
    ++res.evaluations;
    if (evaluate(l, img[l], T, alpha, beta, e, true) < 6) continue;
    double c0 = cost(e);
    for (int it = 0; it < cfg_.max_iterations; ++it, ++res.iterations) {
      normalEquations(e, H, g);
      bool improved = false;
      for (int tries = 0; tries < 5 && !improved; ++tries) {
        Eigen::MatrixXd Hs = H.topLeftCorner(np, np);
        Hs.diagonal() *= 1.0 + lm.lambda();
        const Eigen::VectorXd delta = -Hs.ldlt().solve(g.head(np));
        if (!delta.allFinite()) break;
        const SE3 T_new = SE3::exp(delta.head<6>()) * T;
        const double a_new = np == 8 ? alpha + delta[6] : alpha, b_new = np == 8 ? beta + delta[7] : beta;
        // A gain of zero or less has no logarithm (the window's brightness parameter): never stepped to.
        if (!(a_new > 0)) {
          lm.rejected();
          continue;
        }
        ++res.evaluations;
        if (evaluate(l, img[l], T_new, a_new, b_new, e_new, true) < 6) {
          lm.rejected();
          continue;
        }
        const double c1 = cost(e_new);
        if (c1 < c0) {
          T = T_new, alpha = a_new, beta = b_new;
          std::swap(e, e_new);
          const bool converged = c0 - c1 < cfg_.convergence * c0 || delta.head<6>().norm() < 1e-7;
          c0 = c1;
          lm.accepted();
          improved = !converged;
          if (converged) it = cfg_.max_iterations;
        } else {
          lm.rejected();
          if (delta.head<6>().norm() < cfg_.min_step) break;  // only more damping would follow
        }
      }
      if (!improved) break;
    }
  }
  double ss = 0;
  res.residuals = 0;
  for (int ch = 0; ch < kReductionChunks; ++ch)
    ss += e.ss[ch], res.residuals += static_cast<int>(e.count[ch]);
  res.rmse = res.residuals == 0 ? 1e9 : std::sqrt(ss / res.residuals);
  res.ok = res.residuals >= cfg_.min_residuals && res.rmse <= cfg_.max_rmse && T.translation().allFinite() &&
           alpha >= cfg_.min_gain;
  return res;
}

}  // namespace eds
