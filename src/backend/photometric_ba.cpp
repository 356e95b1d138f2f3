#include "backend/photometric_ba.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>

#include "frontend/frame_tracker.hpp"  // sampleBilinear

namespace eds {

namespace {
constexpr int kPattern[8][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0}, {0, 0}, {2, 0}, {-1, 1}, {0, 2}};
constexpr int kFrameParams = 8;  // pose (6), a, b

double huberCost(double r, double d) {
  const double a = std::abs(r);
  return a <= d ? 0.5 * r * r : d * (a - 0.5 * d);
}
}  // namespace

PhotometricBA::PhotometricBA(const CameraModel& pinhole, BaConfig cfg) : cam_(pinhole), cfg_(cfg) {
  if (cam_.distortion != Distortion::kNone)
    throw std::invalid_argument("photometric BA: undistorted camera only");
  if (cfg_.iterations < 1 || !(cfg_.huber > 0))
    throw std::invalid_argument("photometric BA: bad configuration");
}

bool PhotometricBA::evaluate(const std::vector<BaFrame>& frames, const BaPoint& p, int target,
                             Eigen::Matrix<double, 8, 1>& r, Eigen::Matrix<double, 8, 17>* J) const {
  const BaFrame& H = frames.at(p.host);
  const BaFrame& T = frames.at(target);
  const SE3 T_t_w = T.T_w_c.inverse();
  const SE3 T_t_h = T_t_w * H.T_w_c;
  const Mat3 R_t_w = T_t_w.rotationMatrix(), R_t_h = T_t_h.rotationMatrix();
  const double e = std::exp(T.a - H.a);
  const int W = H.image.cols, Hh = H.image.rows;
  for (int k = 0; k < 8; ++k) {
    const double uk = p.u + kPattern[k][0], vk = p.v + kPattern[k][1];
    if (uk < 0 || vk < 0 || uk >= W - 1 || vk >= Hh - 1) return false;
    double hx, hy;
    const double I_h = sampleBilinear(H.image, uk, vk, hx, hy);
    const Vec3 x_h((uk - cam_.cx) / cam_.fx, (vk - cam_.cy) / cam_.fy, 1.0);
    const Vec3 X_h = x_h / p.inv_depth;
    const Vec3 X_t = T_t_h * X_h;
    if (X_t.z() <= 1e-6) return false;
    const double iz = 1.0 / X_t.z();
    const double ut = cam_.fx * X_t.x() * iz + cam_.cx, vt = cam_.fy * X_t.y() * iz + cam_.cy;
    if (!(ut >= 1 && vt >= 1 && ut < T.image.cols - 2 && vt < T.image.rows - 2)) return false;
    double dx, dy;
    const double I_t = sampleBilinear(T.image, ut, vt, dx, dy);
    r[k] = I_t - T.b - e * (I_h - H.b);
    if (J) {
      const Eigen::RowVector3d dI_dX(dx * cam_.fx * iz, dy * cam_.fy * iz,
                                     -(dx * cam_.fx * X_t.x() + dy * cam_.fy * X_t.y()) * iz * iz);
      const Eigen::RowVector3d g = dI_dX * R_t_w;
      const Vec3 X_w = H.T_w_c * X_h;
      // X_t = T_w_t^-1 X_w: a left perturbation of the target moves X_t by -R_t_w (δv + δω x X_w),
      // one of the host moves X_w by (δv + δω x X_w).
      const Eigen::RowVector3d gx = X_w.cross(g.transpose()).transpose();
      J->block<1, 3>(k, 0) = g;
      J->block<1, 3>(k, 3) = gx;
      (*J)(k, 6) = e * (I_h - H.b);
      (*J)(k, 7) = e;
      J->block<1, 3>(k, 8) = -g;
      J->block<1, 3>(k, 11) = -gx;
      (*J)(k, 14) = -e * (I_h - H.b);
      (*J)(k, 15) = -1.0;
      (*J)(k, 16) = dI_dX * (R_t_h * (-x_h / (p.inv_depth * p.inv_depth)));
    }
  }
  return true;
}

BaStats PhotometricBA::optimize(std::vector<BaFrame>& frames, std::vector<BaPoint>& points) const {
  BaStats stats;
  const int F = static_cast<int>(frames.size());
  // Frame parameter index (-1 for fixed frames): the system only holds the free ones.
  std::vector<int> slot(F, -1);
  int nf = 0;
  for (int f = 0; f < F; ++f)
    if (!frames[f].fixed) slot[f] = nf++;
  const int dim = nf * kFrameParams;
  const double d = cfg_.huber, c2 = cfg_.grad_weight_c * cfg_.grad_weight_c;

  // Gradient weights per point and pattern pixel, from the host image (fixed during the solve).
  const auto gradWeight = [&](const BaPoint& p, int k) {
    double gx, gy;
    sampleBilinear(frames[p.host].image, p.u + kPattern[k][0], p.v + kPattern[k][1], gx, gy);
    return c2 / (c2 + gx * gx + gy * gy);
  };
  const auto totalCost = [&](const std::vector<BaFrame>& fr, const std::vector<BaPoint>& pts, double* rmse,
                             int* count) {
    double cost = 0, ss = 0;
    int n = 0;
    Eigen::Matrix<double, 8, 1> r;
    for (const BaPoint& p : pts) {
      if (p.outlier) continue;
      for (int t : p.targets) {
        if (!evaluate(fr, p, t, r, nullptr)) continue;
        for (int k = 0; k < 8; ++k) {
          cost += gradWeight(p, k) * huberCost(r[k], d);
          ss += r[k] * r[k];
          ++n;
        }
      }
    }
    if (rmse) *rmse = n ? std::sqrt(ss / n) : 0.0;
    if (count) *count = n;
    return cost;
  };

  double cost = totalCost(frames, points, &stats.initial_rmse, &stats.residuals);
  double lambda = cfg_.lambda_initial;
  Eigen::MatrixXd S(dim, dim);
  Eigen::VectorXd s(dim);
  std::vector<double> Hpp(points.size()), bp(points.size());
  std::vector<Eigen::VectorXd> Hfp(points.size());
  Eigen::Matrix<double, 8, 1> r;
  Eigen::Matrix<double, 8, 17> J;
  for (int it = 0; it < cfg_.iterations; ++it, ++stats.iterations) {
    // Normal equations, points kept apart for the Schur complement.
    Eigen::MatrixXd Hff = Eigen::MatrixXd::Zero(dim, dim);
    Eigen::VectorXd bf = Eigen::VectorXd::Zero(dim);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const BaPoint& p = points[i];
      Hpp[i] = bp[i] = 0;
      Hfp[i] = Eigen::VectorXd::Zero(dim);
      if (p.outlier) continue;
      for (int t : p.targets) {
        if (!evaluate(frames, p, t, r, &J)) continue;
        const int sh = slot[p.host], st = slot[t];
        for (int k = 0; k < 8; ++k) {
          const double a = std::abs(r[k]);
          const double w = gradWeight(p, k) * (a <= d ? 1.0 : d / a);
          const Eigen::Matrix<double, 1, 8> Jh = J.block<1, 8>(k, 0), Jt = J.block<1, 8>(k, 8);
          const double Jr = J(k, 16);
          if (sh >= 0) {
            Hff.block<8, 8>(sh * 8, sh * 8) += w * Jh.transpose() * Jh;
            bf.segment<8>(sh * 8) += w * r[k] * Jh.transpose();
            Hfp[i].segment<8>(sh * 8) += w * Jr * Jh.transpose();
          }
          if (st >= 0) {
            Hff.block<8, 8>(st * 8, st * 8) += w * Jt.transpose() * Jt;
            bf.segment<8>(st * 8) += w * r[k] * Jt.transpose();
            Hfp[i].segment<8>(st * 8) += w * Jr * Jt.transpose();
          }
          if (sh >= 0 && st >= 0) {
            Hff.block<8, 8>(sh * 8, st * 8) += w * Jh.transpose() * Jt;
            Hff.block<8, 8>(st * 8, sh * 8) += w * Jt.transpose() * Jh;
          }
          Hpp[i] += w * Jr * Jr;
          bp[i] += w * Jr * r[k];
        }
      }
    }
    bool accepted = false;
    for (int tries = 0; tries < 5 && !accepted; ++tries) {
      // Levenberg damping on every diagonal entry, then the Schur complement over the points.
      S = Hff;
      S.diagonal() *= 1.0 + lambda;
      S.diagonal().array() += 1e-9;
      s = bf;
      std::vector<double> hpp_d(points.size());
      for (std::size_t i = 0; i < points.size(); ++i) {
        hpp_d[i] = Hpp[i] * (1.0 + lambda) + 1e-12;
        if (Hpp[i] <= 0) continue;
        S.noalias() -= Hfp[i] * Hfp[i].transpose() / hpp_d[i];
        s.noalias() -= Hfp[i] * (bp[i] / hpp_d[i]);
      }
      const Eigen::VectorXd df = dim > 0 ? Eigen::VectorXd(-S.ldlt().solve(s)) : Eigen::VectorXd();
      if (!df.allFinite()) {
        lambda *= 10;
        continue;
      }
      std::vector<BaFrame> f_new = frames;
      std::vector<BaPoint> p_new = points;
      for (int f = 0; f < F; ++f) {
        if (slot[f] < 0) continue;
        const Eigen::Matrix<double, 8, 1> x = df.segment<8>(slot[f] * 8);
        f_new[f].T_w_c = SE3::exp(x.head<6>()) * frames[f].T_w_c;
        f_new[f].a += x[6];
        f_new[f].b += x[7];
      }
      for (std::size_t i = 0; i < points.size(); ++i) {
        if (Hpp[i] <= 0) continue;
        const double dr = -(bp[i] + Hfp[i].dot(df)) / hpp_d[i];
        p_new[i].inv_depth = std::max(1e-4, points[i].inv_depth + dr);
      }
      const double cost_new = totalCost(f_new, p_new, nullptr, nullptr);
      if (cost_new < cost) {
        frames.swap(f_new);
        points.swap(p_new);
        accepted = true;
        const bool converged = cost - cost_new < 1e-6 * cost;
        cost = cost_new;
        lambda = std::max(1e-8, lambda * 0.3);
        if (converged) it = cfg_.iterations;
      } else {
        lambda *= 10;
      }
    }
    if (!accepted) break;
  }
  // Outliers: observations whose pattern does not match any more (occlusion, wrong depth).
  for (BaPoint& p : points) {
    if (p.outlier) continue;
    std::vector<int> keep;
    for (int t : p.targets) {
      if (evaluate(frames, p, t, r, nullptr) && std::sqrt(r.squaredNorm() / 8) <= cfg_.outlier_energy)
        keep.push_back(t);
      else
        ++stats.outliers_removed;
    }
    p.targets.swap(keep);
    if (p.targets.empty()) p.outlier = true;
  }
  totalCost(frames, points, &stats.final_rmse, &stats.residuals);
  return stats;
}

}  // namespace eds
