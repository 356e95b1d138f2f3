#include "backend/photometric_ba.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdlib>
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

Eigen::VectorXd BaPrior::delta(const std::vector<BaFrame>& fr) const {
  Eigen::VectorXd x(8 * frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const BaFrame& f = fr.at(frames[i]);
    x.segment<6>(8 * i) = (f.T_w_c * T0[i].inverse()).log();
    x[8 * i + 6] = f.a - a0[i];
    x[8 * i + 7] = f.b - b0[i];
  }
  return x;
}

double BaPrior::energy(const std::vector<BaFrame>& fr) const {
  if (empty()) return 0.0;
  const Eigen::VectorXd x = delta(fr);
  return b.dot(x) + 0.5 * x.dot(H * x);
}

void BaPrior::eraseFrameIndex(int removed) {
  for (int& f : frames) {
    if (f == removed) throw std::logic_error("BaPrior: erasing a frame the prior still holds");
    if (f > removed) --f;
  }
}

// Normal equations of the photometric terms with the points kept apart (one inverse depth each), so
// that they can be eliminated by the Schur complement.
struct NormalEquations {
  Eigen::MatrixXd Hff;
  Eigen::VectorXd bf;
  std::vector<double> Hpp, bp;
  std::vector<Eigen::VectorXd> Hfp;
};

BaStats PhotometricBA::optimize(std::vector<BaFrame>& frames, std::vector<BaPoint>& points,
                                const BaPrior* prior) const {
  BaStats stats;
  const int F = static_cast<int>(frames.size());
  // Frame parameter index (-1 for fixed frames): the system only holds the free ones.
  std::vector<int> slot(F, -1);
  int nf = 0;
  for (int f = 0; f < F; ++f)
    if (!frames[f].fixed) slot[f] = nf++;
  const int dim = nf * kFrameParams;
  const double d = cfg_.huber, c2 = cfg_.grad_weight_c * cfg_.grad_weight_c;
  if (prior && prior->empty()) prior = nullptr;

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
      if (p.prior_weight > 0) {
        const double e = p.inv_depth - p.prior_inv_depth;
        cost += 0.5 * p.prior_weight * e * e;
      }
      for (int t : p.targets) {
        if (!evaluate(fr, p, t, r, nullptr)) continue;
        for (int k = 0; k < 8; ++k) {
          cost += gradWeight(p, k) * huberCost(r[k], d);
          ss += r[k] * r[k];
          ++n;
        }
      }
    }
    if (prior) cost += prior->energy(fr);
    if (rmse) *rmse = n ? std::sqrt(ss / n) : 0.0;
    if (count) *count = n;
    return cost;
  };

  double cost = totalCost(frames, points, &stats.initial_rmse, &stats.residuals);
  double lambda = cfg_.lambda_initial;
  Eigen::MatrixXd S(dim, dim);
  Eigen::VectorXd s(dim);
  NormalEquations ne;
  for (int it = 0; it < cfg_.iterations; ++it, ++stats.iterations) {
    accumulate(frames, points, slot, dim, ne);
    if (prior) {
      // Gradient b + Hx at the current state; Hessian blocks between free frames only.
      const Eigen::VectorXd g = prior->b + prior->H * prior->delta(frames);
      const int np = static_cast<int>(prior->frames.size());
      for (int i = 0; i < np; ++i) {
        const int si = slot[prior->frames[i]];
        if (si < 0) continue;
        ne.bf.segment<8>(si * 8) += g.segment<8>(8 * i);
        for (int j = 0; j < np; ++j) {
          const int sj = slot[prior->frames[j]];
          if (sj >= 0) ne.Hff.block<8, 8>(si * 8, sj * 8) += prior->H.block<8, 8>(8 * i, 8 * j);
        }
      }
    }
    bool accepted = false;
    for (int tries = 0; tries < 5 && !accepted; ++tries) {
      // Levenberg damping on every diagonal entry, then the Schur complement over the points.
      S = ne.Hff;
      S.diagonal() *= 1.0 + lambda;
      S.diagonal().array() += 1e-9;
      s = ne.bf;
      std::vector<double> hpp_d(points.size());
      for (std::size_t i = 0; i < points.size(); ++i) {
        hpp_d[i] = ne.Hpp[i] * (1.0 + lambda) + 1e-12;
        if (ne.Hpp[i] <= 0) continue;
        S.noalias() -= ne.Hfp[i] * ne.Hfp[i].transpose() / hpp_d[i];
        s.noalias() -= ne.Hfp[i] * (ne.bp[i] / hpp_d[i]);
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
        if (ne.Hpp[i] <= 0) continue;
        const double dr = -(ne.bp[i] + (dim > 0 ? ne.Hfp[i].dot(df) : 0.0)) / hpp_d[i];
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
  Eigen::Matrix<double, 8, 1> r;
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

void PhotometricBA::accumulate(const std::vector<BaFrame>& frames, const std::vector<BaPoint>& points,
                               const std::vector<int>& slot, int dim, NormalEquations& ne,
                               int only_host) const {
  const double d = cfg_.huber, c2 = cfg_.grad_weight_c * cfg_.grad_weight_c;
  ne.Hff = Eigen::MatrixXd::Zero(dim, dim);
  ne.bf = Eigen::VectorXd::Zero(dim);
  ne.Hpp.assign(points.size(), 0.0);
  ne.bp.assign(points.size(), 0.0);
  ne.Hfp.resize(points.size());
  Eigen::Matrix<double, 8, 1> r;
  Eigen::Matrix<double, 8, 17> J;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const BaPoint& p = points[i];
    ne.Hfp[i] = Eigen::VectorXd::Zero(dim);
    if (p.outlier || (only_host >= 0 && p.host != only_host)) continue;
    if (p.prior_weight > 0) {
      ne.Hpp[i] += p.prior_weight;
      ne.bp[i] += p.prior_weight * (p.inv_depth - p.prior_inv_depth);
    }
    for (int t : p.targets) {
      if (!evaluate(frames, p, t, r, &J)) continue;
      const int sh = slot[p.host], st = slot[t];
      for (int k = 0; k < 8; ++k) {
        double gx, gy;
        sampleBilinear(frames[p.host].image, p.u + kPattern[k][0], p.v + kPattern[k][1], gx, gy);
        const double a = std::abs(r[k]);
        const double w = c2 / (c2 + gx * gx + gy * gy) * (a <= d ? 1.0 : d / a);
        const Eigen::Matrix<double, 1, 8> Jh = J.block<1, 8>(k, 0), Jt = J.block<1, 8>(k, 8);
        const double Jr = J(k, 16);
        if (sh >= 0) {
          ne.Hff.block<8, 8>(sh * 8, sh * 8) += w * Jh.transpose() * Jh;
          ne.bf.segment<8>(sh * 8) += w * r[k] * Jh.transpose();
          ne.Hfp[i].segment<8>(sh * 8) += w * Jr * Jh.transpose();
        }
        if (st >= 0) {
          ne.Hff.block<8, 8>(st * 8, st * 8) += w * Jt.transpose() * Jt;
          ne.bf.segment<8>(st * 8) += w * r[k] * Jt.transpose();
          ne.Hfp[i].segment<8>(st * 8) += w * Jr * Jt.transpose();
        }
        if (sh >= 0 && st >= 0) {
          ne.Hff.block<8, 8>(sh * 8, st * 8) += w * Jh.transpose() * Jt;
          ne.Hff.block<8, 8>(st * 8, sh * 8) += w * Jt.transpose() * Jh;
        }
        ne.Hpp[i] += w * Jr * Jr;
        ne.bp[i] += w * Jr * r[k];
      }
    }
  }
}

BaPrior PhotometricBA::marginalize(const std::vector<BaFrame>& frames, const std::vector<BaPoint>& points,
                                   const BaPrior* prior, int m) const {
  const int F = static_cast<int>(frames.size());
  if (m < 0 || m >= F) throw std::out_of_range("marginalize: no such frame");
  // Every frame is a variable here (fixed or not): the prior must hold the information about all of
  // them, whichever the window holds fixed later.
  std::vector<int> slot(F);
  for (int f = 0; f < F; ++f) slot[f] = f;
  const int dim = F * kFrameParams;
  NormalEquations ne;
  accumulate(frames, points, slot, dim, ne, m);
  Eigen::MatrixXd H = ne.Hff;
  Eigen::VectorXd b = ne.bf;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (ne.Hpp[i] <= 1e-12) continue;
    H.noalias() -= ne.Hfp[i] * ne.Hfp[i].transpose() / ne.Hpp[i];
    b.noalias() -= ne.Hfp[i] * (ne.bp[i] / ne.Hpp[i]);
  }
  if (prior && !prior->empty()) {
    const Eigen::VectorXd g = prior->b + prior->H * prior->delta(frames);
    const int np = static_cast<int>(prior->frames.size());
    for (int i = 0; i < np; ++i) {
      const int si = prior->frames[i];
      b.segment<8>(si * 8) += g.segment<8>(8 * i);
      for (int j = 0; j < np; ++j)
        H.block<8, 8>(si * 8, prior->frames[j] * 8) += prior->H.block<8, 8>(8 * i, 8 * j);
    }
  }
  // Schur complement of frame m: its block is regularized slightly so that a frame seen by few
  // residuals (or a gauge direction) does not blow up the inverse.
  std::vector<int> keep;
  for (int f = 0; f < F; ++f)
    if (f != m) keep.push_back(f);
  const int nk = static_cast<int>(keep.size());
  Eigen::MatrixXd Hkk(8 * nk, 8 * nk), Hkm(8 * nk, 8);
  Eigen::VectorXd bk(8 * nk);
  for (int i = 0; i < nk; ++i) {
    bk.segment<8>(8 * i) = b.segment<8>(8 * keep[i]);
    Hkm.block<8, 8>(8 * i, 0) = H.block<8, 8>(8 * keep[i], 8 * m);
    for (int j = 0; j < nk; ++j) Hkk.block<8, 8>(8 * i, 8 * j) = H.block<8, 8>(8 * keep[i], 8 * keep[j]);
  }
  Eigen::Matrix<double, 8, 8> Hmm = H.block<8, 8>(8 * m, 8 * m);
  Hmm.diagonal().array() += 1e-9 + 1e-6 * Hmm.diagonal().array();
  const Eigen::LDLT<Eigen::Matrix<double, 8, 8>> ldlt(Hmm);
  BaPrior out;
  out.frames = keep;
  out.H = Hkk - Hkm * ldlt.solve(Hkm.transpose());
  out.H = 0.5 * (out.H + out.H.transpose());
  out.b = bk - Hkm * ldlt.solve(b.segment<8>(8 * m));
  for (int f : keep) {
    out.T0.push_back(frames[f].T_w_c);
    out.a0.push_back(frames[f].a);
    out.b0.push_back(frames[f].b);
  }
  return out;
}

}  // namespace eds
