#include "frontend/frame_tracker.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "core/image_sampling.hpp"
#include "core/robust.hpp"
#include "core/weighted_gram.hpp"

namespace eds {

namespace {

// Damping of each pyramid level's solve (core/robust.hpp's schedule).
constexpr double kLambdaInitial = 1e-3, kLambdaFloor = 1e-6;
// DSO's residual pattern #8.
constexpr int kPattern[8][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0}, {0, 0}, {2, 0}, {-1, 1}, {0, 2}};

// JᵀWJ and JᵀWr of n Jacobian rows of 8 (row-major), with the Huber weights of r: the rows go through in
// blocks that fit the first-level cache, each turned into columns for core/weighted_gram.hpp.
void normalEquations(const double* J, const double* r, std::size_t n, double huber,
                     Eigen::Matrix<double, 8, 8>& H, Eigen::Matrix<double, 8, 1>& g) {
  constexpr std::size_t kBlock = 64;
  alignas(32) double col[8][kBlock], wcol[8][kBlock], wr[kBlock];
  const double* cols[8];
  const double* wcols[8];
  for (int c = 0; c < 8; ++c) cols[c] = col[c], wcols[c] = wcol[c];
  H.setZero(), g.setZero();
  for (std::size_t b0 = 0; b0 < n; b0 += kBlock) {
    const std::size_t m = std::min(kBlock, n - b0);
    for (std::size_t i = 0; i < m; ++i) {
      const double* row = J + (b0 + i) * 8;
      const double w = huberWeight(r[b0 + i], huber);
      for (int c = 0; c < 8; ++c) col[c][i] = row[c], wcol[c][i] = w * row[c];
      wr[i] = w * r[b0 + i];
    }
    addWeightedGram<8>(cols, wcols, wr, m, H, g);
  }
}
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
  points_.assign(cfg_.levels, {});
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
        const double z = 1.0 / p.inv_depth;
        LevelPoint lp;
        lp.p_kf = c.pinholeRay(u, v) * z;
        lp.ref = sampleBilinear(img[l], u, v);
        points_[l].push_back(lp);
      }
    }
  }
  if (points_[0].empty()) throw std::invalid_argument("frame tracker: keyframe has no point with depth");
}

int FrameTracker::evaluate(int level, const cv::Mat& img, const SE3& T, double alpha, double beta,
                           std::vector<double>& r, std::vector<Eigen::Matrix<double, 1, 8>>* J) const {
  const CameraModel c = levelCamera(level);
  const Mat3 R = T.rotationMatrix();
  const Vec3 t = T.translation();
  r.clear();
  if (J) J->clear();
  for (const LevelPoint& lp : points_[level]) {
    const Vec3 q = R * lp.p_kf + t;
    if (q.z() <= 1e-6) continue;
    const double iz = 1.0 / q.z();
    const double u = c.fx * q.x() * iz + c.cx, v = c.fy * q.y() * iz + c.cy;
    if (!(u >= 1 && v >= 1 && u < c.width - 2 && v < c.height - 2)) continue;
    double dx, dy;
    const double I = sampleBilinear(img, u, v, dx, dy);
    if (!std::isfinite(I)) continue;  // a pixel marked as holding no information (clipped)
    r.push_back(I - (alpha * lp.ref + beta));
    if (J) {
      const Vec3 dI_dq(dx * c.fx * iz, dy * c.fy * iz, -(dx * c.fx * q.x() + dy * c.fy * q.y()) * iz * iz);
      Eigen::Matrix<double, 1, 8> row;
      row.head<3>() = dI_dq.transpose();
      row.segment<3>(3) = q.cross(dI_dq).transpose();
      row(6) = -lp.ref;
      row(7) = -1.0;
      J->push_back(row);
    }
  }
  return static_cast<int>(r.size());
}

FrameTrackResult FrameTracker::track(const cv::Mat& frame, SE3& T, double& alpha, double& beta,
                                     int levels) const {
  if (points_.empty()) throw std::logic_error("FrameTracker::track before setKeyframe");
  std::vector<cv::Mat> img;
  pyramid(frame, img);
  FrameTrackResult res;
  std::vector<double> r, r_new;
  std::vector<Eigen::Matrix<double, 1, 8>> J, J_new;
  const int np = cfg_.affine ? 8 : 6;
  const double d = cfg_.huber;
  const auto cost = [d](const std::vector<double>& rr) {
    double c = 0;
    for (double x : rr) c += huberCost(x, d);
    return c / std::max<std::size_t>(1, rr.size());  // mean: the point count changes with the pose
  };
  static_assert(sizeof(Eigen::Matrix<double, 1, 8>) == 8 * sizeof(double), "Jacobian rows must be packed");
  Eigen::Matrix<double, 8, 8> H;
  Eigen::Matrix<double, 8, 1> g;
  const int start = levels > 0 ? std::min(levels, cfg_.levels) - 1 : cfg_.levels - 1;
  for (int l = start; l >= 0; --l) {
    LmDamping lm(kLambdaInitial, kLambdaFloor);
    ++res.evaluations;
    if (evaluate(l, img[l], T, alpha, beta, r, &J) < 6) continue;
    double c0 = cost(r);
    for (int it = 0; it < cfg_.max_iterations; ++it, ++res.iterations) {
      normalEquations(J.data()->data(), r.data(), r.size(), d, H, g);
      bool improved = false;
      for (int tries = 0; tries < 5 && !improved; ++tries) {
        Eigen::MatrixXd Hs = H.topLeftCorner(np, np);
        Hs.diagonal() *= 1.0 + lm.lambda();
        const Eigen::VectorXd delta = -Hs.ldlt().solve(g.head(np));
        if (!delta.allFinite()) break;
        const SE3 T_new = SE3::exp(delta.head<6>()) * T;
        const double a_new = np == 8 ? alpha + delta[6] : alpha, b_new = np == 8 ? beta + delta[7] : beta;
        ++res.evaluations;
        if (evaluate(l, img[l], T_new, a_new, b_new, r_new, &J_new) < 6) {
          lm.rejected();
          continue;
        }
        const double c1 = cost(r_new);
        if (c1 < c0) {
          T = T_new, alpha = a_new, beta = b_new;
          r.swap(r_new);
          J.swap(J_new);
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
  for (double x : r) ss += std::min(x * x, d * d);
  res.residuals = static_cast<int>(r.size());
  res.rmse = r.empty() ? 1e9 : std::sqrt(ss / r.size());
  res.ok = res.residuals >= cfg_.min_residuals && res.rmse <= cfg_.max_rmse && T.translation().allFinite();
  return res;
}

}  // namespace eds
