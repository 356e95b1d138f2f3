#include "backend/photometric_ba.hpp"

#include <Eigen/Cholesky>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <optional>
#include <stdexcept>

#include "backend/ba_pair_geometry.hpp"
#include "backend/normal_equations.hpp"
#include "core/image_sampling.hpp"
#include "core/parallel.hpp"
#include "core/robust.hpp"

namespace eds {

namespace {
constexpr int kPattern[8][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0}, {0, 0}, {2, 0}, {-1, 1}, {0, 2}};

constexpr double kLambdaFloor = 1e-8;

}  // namespace

PhotometricBA::PhotometricBA(const CameraModel& pinhole, BaConfig cfg) : cam_(pinhole), cfg_(cfg) {
  if (cam_.distortion != Distortion::kNone)
    throw std::invalid_argument("photometric BA: undistorted camera only");
  if (cfg_.iterations < 1 || !(cfg_.huber > 0))
    throw std::invalid_argument("photometric BA: bad configuration");
}

namespace {
std::vector<BaFrame> linearizationFrames(const std::vector<BaFrame>& frames, const BaPrior* prior) {
  std::vector<BaFrame> lin = frames;
  for (std::size_t i = 0; i < prior->frames.size(); ++i) {
    BaFrame& f = lin[prior->frames[i]];
    f.T_w_c = prior->T0[i], f.a = prior->a0[i], f.b = prior->b0[i];
  }
  return lin;
}
}  // namespace

bool PhotometricBA::evaluateCore(const std::vector<BaFrame>& frames, const PairTransforms& pairs, int host,
                                 float u, float v, double rho, int target, Eigen::Matrix<double, 8, 1>& r,
                                 PairJacobian* J, const double* host_values,
                                 const LinearizationState* lin) const {
  const BaFrame& H = frames[host];
  const BaFrame& T = frames[target];
  const int pi = host * pairs.F + target;
  const Mat3& R_t_h = pairs.R_t_h[pi];
  const Vec3 t_t_h = pairs.T_t_h[pi].translation();
  // The pattern spans ±2 px around (u, v).
  if (u - 2.0 < 0 || v - 2.0 < 0 || u + 2.0 >= H.image.cols - 1 || v + 2.0 >= H.image.rows - 1) return false;
  // A pattern pixel's ray is the centre's plus (δu/fx, δv/fy, 0), so its point in the target (and in
  // the world, for the Jacobian) follows from the centre's through two columns of a rotation: no
  // division and no rotation per pixel. The eight pixels go through as arrays (vector instructions).
  const Arr8 du = Eigen::Map<const Arr8>(kPatternU), dv = Eigen::Map<const Arr8>(kPatternV);
  const double inv_rho = 1.0 / rho;
  const Vec3 x_c = cam_.pinholeRay(u, v);
  const Vec3 Rx_c = R_t_h * x_c, R_du = R_t_h.col(0) / cam_.fx, R_dv = R_t_h.col(1) / cam_.fy;
  Arr8 RX[3], X[3];  // R_t_h x_h per pixel, and the point in the target
  for (int c = 0; c < 3; ++c) {
    RX[c] = Rx_c[c] + du * R_du[c] + dv * R_dv[c];
    X[c] = RX[c] * inv_rho + t_t_h[c];
  }
  if (!(X[2] > 1e-6).all()) return false;
  const Arr8 iz = X[2].inverse();
  const Arr8 ut = cam_.fx * X[0] * iz + cam_.cx, vt = cam_.fy * X[1] * iz + cam_.cy;
  if (!((ut >= 1) && (vt >= 1) && (ut < T.image.cols - 2) && (vt < T.image.rows - 2)).all()) return false;
  Arr8 I_t, dx, dy, I_h;
  for (int k = 0; k < 8; ++k) {
    I_t[k] = sampleBilinear(T.image, ut[k], vt[k], dx[k], dy[k]);
    I_h[k] =
        host_values ? host_values[k] : static_cast<double>(sampleBilinear(H.image, u + du[k], v + dv[k]));
  }
  r = (I_t - T.b - pairs.e[pi] * (I_h - H.b)).matrix();
  if (J) pairJacobian(cam_, frames, pairs, host, target, x_c, inv_rho, {RX, X, iz, I_h, dx, dy}, *J, lin);
  return true;
}

bool PhotometricBA::evaluate(const std::vector<BaFrame>& frames, const BaPoint& p, int target,
                             Eigen::Matrix<double, 8, 1>& r, Eigen::Matrix<double, 8, 17>* J) const {
  if (p.host < 0 || p.host >= static_cast<int>(frames.size()) || target < 0 ||
      target >= static_cast<int>(frames.size()))
    throw std::out_of_range("photometric BA: frame index out of range");
  PairJacobian Jc;
  if (!evaluateCore(frames, PairTransforms(frames), p.host, p.u, p.v, p.inv_depth, target, r,
                    J ? &Jc : nullptr))
    return false;
  if (J) {
    // Host [A, e], target [-A, -1] (see PairJacobian), inverse depth last.
    J->leftCols<7>() = Jc.A;
    J->col(7).setConstant(Jc.e);
    J->middleCols<7>(8) = -Jc.A;
    J->col(15).setConstant(-1.0);
    J->col(16) = Jc.d_rho;
  }
  return true;
}

std::vector<double> PhotometricBA::patternRms(const std::vector<BaFrame>& frames,
                                              const std::vector<BaPoint>& points, int target) const {
  if (target < 0 || target >= static_cast<int>(frames.size()))
    throw std::out_of_range("photometric BA: frame index out of range");
  for (const BaPoint& p : points)
    if (p.host < 0 || p.host >= static_cast<int>(frames.size()))
      throw std::out_of_range("photometric BA: point host out of range");
  const PairTransforms pairs(frames);
  std::vector<double> rms(points.size(), std::numeric_limits<double>::quiet_NaN());
  forEachChunk(points.size(), [&](int, std::size_t begin, std::size_t end) {
    Eigen::Matrix<double, 8, 1> r;
    for (std::size_t i = begin; i < end; ++i) {
      const BaPoint& p = points[i];
      if (p.host != target && evaluateCore(frames, pairs, p.host, p.u, p.v, p.inv_depth, target, r, nullptr))
        rms[i] = std::sqrt(r.squaredNorm() / 8);
    }
  });
  return rms;
}

// The robust cost of the photometric terms and the squares of their residuals, summed in the order of
// the points so that cost() and accumulate() give the same figure to the last bit.
struct CostSums {
  double c = 0, ss = 0;
  int n = 0;
  void addPointPrior(const BaPoint& p, double rho) {
    const double e = rho - p.prior_inv_depth;
    c += 0.5 * p.prior_weight * e * e;
  }
  void addPattern(const Eigen::Matrix<double, 8, 1>& r, const HostPattern& g, double huber) {
    for (int k = 0; k < 8; ++k) {
      c += g.w[k] * huberCost(r[k], huber);
      ss += r[k] * r[k];
      ++n;
    }
  }
  static CostSums total(const std::array<CostSums, kReductionChunks>& part) {
    CostSums t;
    for (const CostSums& s : part) t.c += s.c, t.ss += s.ss, t.n += s.n;
    return t;
  }
  double rmse() const { return n ? std::sqrt(ss / n) : 0.0; }
  // The whole energy: these terms and the prior's (if any) at `frames`.
  double energy(const BaPrior* prior, const std::vector<BaFrame>& frames) const {
    return c + (prior ? prior->energy(frames) : 0.0);
  }
};

namespace {

// A (host, target) frame pair's share of JᵀWJ and JᵀWr. Its residuals' Jacobians (PairJacobian) have
// host columns [A, e] and target columns [-A, -1] with one e for the whole pair, so the three 8×8 blocks
// and both gradients follow from the sums of [A, 1]ᵀW[A, 1] and [A, 1]ᵀWr over its residuals (DSO's
// trick): they are expanded once per pair, not once per residual.
struct PairSums {
  Eigen::Matrix<double, 8, 8> S = Eigen::Matrix<double, 8, 8>::Zero();
  Eigen::Matrix<double, 8, 1> v = Eigen::Matrix<double, 8, 1>::Zero();
  double e = 1;
  bool used = false;
  PairSums& operator+=(const PairSums& o) {
    if (!o.used) return *this;
    S += o.S, v += o.v, e = o.e, used = true;
    return *this;
  }
};

// One (point, target) residual pair: the Gram matrix of [A, 1] against [A, 1, r, ∂r/∂ρ]; its frame part
// goes to the pair's sums, its point part (the point's column of Hfp, Hpp, bp) straight to the normal
// equations. [A, 1] is taken transposed (parameters by pattern pixels) so that every column of the
// product is one contiguous 8-vector: the compiler vectorizes it without horizontal sums.
// sh, st: the slots of host and target (< 0: constant frame).
void addResiduals(const PairJacobian& J, const Eigen::Matrix<double, 8, 1>& r,
                  const Eigen::Matrix<double, 8, 1>& w, int sh, int st, Eigen::Index i, PairSums& ps,
                  NormalEquations& ne) {
  Eigen::Matrix<double, 8, 8> At;
  At.topRows<7>() = J.A.transpose();
  At.row(7).setOnes();
  Eigen::Matrix<double, 8, 10> WB;
  WB.leftCols<7>() = w.asDiagonal() * J.A;
  WB.col(7) = w;
  WB.col(8) = w.cwiseProduct(r);
  WB.col(9) = w.cwiseProduct(J.d_rho);
  const Eigen::Matrix<double, 8, 10> G = At.lazyProduct(WB);  // [S | v | the point's column]
  ps.S += G.leftCols<8>();
  ps.v += G.col(8);
  ps.e = J.e;
  ps.used = true;
  if (sh >= 0) {
    ne.Hfp.col(i).segment<7>(sh * 8) += G.block<7, 1>(0, 9);
    ne.Hfp(sh * 8 + 7, i) += J.e * G(7, 9);
  }
  if (st >= 0) ne.Hfp.col(i).segment<8>(st * 8) -= G.col(9);
  ne.Hpp[i] += J.d_rho.dot(WB.col(9));
  ne.bp[i] += J.d_rho.dot(WB.col(8));
}

// A pair's sums into the frame blocks.
void addPairSums(const PairSums& ps, int sh, int st, NormalEquations& ne) {
  const auto AA = ps.S.topLeftCorner<7, 7>();
  const auto A1 = ps.S.block<7, 1>(0, 7);
  const double s11 = ps.S(7, 7), e = ps.e;
  if (sh >= 0) {
    auto Hhh = ne.Hff.block<8, 8>(sh * 8, sh * 8);
    Hhh.topLeftCorner<7, 7>() += AA;
    Hhh.block<7, 1>(0, 7) += e * A1;
    Hhh.block<1, 7>(7, 0) += e * A1.transpose();
    Hhh(7, 7) += e * e * s11;
    ne.bf.segment<7>(sh * 8) += ps.v.head<7>();
    ne.bf(sh * 8 + 7) += e * ps.v(7);
  }
  if (st >= 0) {
    auto Htt = ne.Hff.block<8, 8>(st * 8, st * 8);
    Htt += ps.S;
    ne.bf.segment<8>(st * 8) -= ps.v;
  }
  if (sh >= 0 && st >= 0) {
    Eigen::Matrix<double, 8, 8> Hht;
    Hht.topLeftCorner<7, 7>() = -AA;
    Hht.block<7, 1>(0, 7) = -A1;
    Hht.block<1, 7>(7, 0) = -e * A1.transpose();
    Hht(7, 7) = -e * s11;
    ne.Hff.block<8, 8>(sh * 8, st * 8) += Hht;
    ne.Hff.block<8, 8>(st * 8, sh * 8) += Hht.transpose();
  }
}

}  // namespace

std::vector<HostPattern> PhotometricBA::hostPatterns(const std::vector<BaFrame>& frames,
                                                     const std::vector<BaPoint>& points) const {
  // √(c²/(c²+|∇I|²)) on the residual is c²/(c²+|∇I|²) on its square: strong edges count less, since
  // small geometric errors make large photometric ones there.
  const double c2 = cfg_.grad_weight_c * cfg_.grad_weight_c;
  std::vector<HostPattern> w(points.size());
  forEachChunk(points.size(), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const BaPoint& p = points[i];
      const cv::Mat& img = frames[p.host].image;
      for (int k = 0; k < 8; ++k) {
        const double uk = p.u + kPattern[k][0], vk = p.v + kPattern[k][1];
        double gx = 0, gy = 0, I = 0;
        if (uk >= 0 && vk >= 0 && uk < img.cols - 1 && vk < img.rows - 1)
          I = sampleBilinear(img, uk, vk, gx, gy);
        w[i].w[k] = c2 / (c2 + gx * gx + gy * gy);
        w[i].I[k] = I;
      }
    }
  });
  return w;
}

double PhotometricBA::cost(const std::vector<BaFrame>& frames, const std::vector<BaPoint>& points,
                           const std::vector<double>& rho, const std::vector<HostPattern>& gw,
                           const BaPrior* prior, double* rmse, int* count) const {
  const PairTransforms pairs(frames);
  std::array<CostSums, kReductionChunks> part{};
  forEachChunk(points.size(), [&](int chunk, std::size_t begin, std::size_t end) {
    CostSums& s = part[chunk];
    Eigen::Matrix<double, 8, 1> r;
    for (std::size_t i = begin; i < end; ++i) {
      const BaPoint& p = points[i];
      if (p.outlier) continue;
      if (p.prior_weight > 0) s.addPointPrior(p, rho[i]);
      for (int t : p.targets)
        if (evaluateCore(frames, pairs, p.host, p.u, p.v, rho[i], t, r, nullptr, gw[i].I.data()))
          s.addPattern(r, gw[i], cfg_.huber);
    }
  });
  const CostSums sum = CostSums::total(part);
  if (rmse) *rmse = sum.rmse();
  if (count) *count = sum.n;
  return sum.energy(prior, frames);
}

// Adds the prior's gradient b + Hx at the current state and its Hessian blocks between free frames.
void PhotometricBA::addPrior(const BaPrior& prior, const std::vector<BaFrame>& frames,
                             const std::vector<int>& slot, NormalEquations& ne) const {
  const Eigen::VectorXd g = prior.b + prior.H * prior.delta(frames);
  const int npf = static_cast<int>(prior.frames.size());
  for (int i = 0; i < npf; ++i) {
    const int si = slot[prior.frames[i]];
    if (si < 0) continue;
    ne.bf.segment<8>(si * 8) += g.segment<8>(8 * i);
    for (int j = 0; j < npf; ++j) {
      const int sj = slot[prior.frames[j]];
      if (sj >= 0) ne.Hff.block<8, 8>(si * 8, sj * 8) += prior.H.block<8, 8>(8 * i, 8 * j);
    }
  }
}

// One Levenberg-Marquardt step: damping on every diagonal entry, the Schur complement over the points,
// the frames' step df and the points' new inverse depths. False if the step is not finite.
bool PhotometricBA::dampedStep(const NormalEquations& ne, double lambda, int dim,
                               const std::vector<double>& rho, StepScratch& w, Eigen::VectorXd& df,
                               std::vector<double>& rho_new) const {
  const std::size_t np = rho.size();
  w.S = ne.Hff;
  w.S.diagonal() *= 1.0 + lambda;
  w.S.diagonal().array() += 1e-9;
  w.s = ne.bf;
  // The points' Schur complement Hfp Hpp⁻¹ Hfpᵀ as one rank-np update (a matrix product, not np
  // rank-one updates).
  w.U.resize(dim, static_cast<Eigen::Index>(np));
  w.v.resize(static_cast<Eigen::Index>(np));
  for (std::size_t i = 0; i < np; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    w.hpp_d[i] = ne.Hpp[i] * (1.0 + lambda) + 1e-12;
    const bool used = ne.Hpp[i] > 0;
    w.U.col(ii) = ne.Hfp.col(ii) * (used ? 1.0 / std::sqrt(w.hpp_d[i]) : 0.0);
    w.v[ii] = used ? ne.bp[i] / w.hpp_d[i] : 0.0;
  }
  if (dim > 0) {
    w.S.selfadjointView<Eigen::Lower>().rankUpdate(w.U, -1.0);
    w.s.noalias() -= ne.Hfp * w.v;
  }
  w.S.triangularView<Eigen::Upper>() = w.S.transpose();
  df = dim > 0 ? Eigen::VectorXd(-w.S.ldlt().solve(w.s)) : Eigen::VectorXd();
  if (!df.allFinite()) return false;
  for (std::size_t i = 0; i < np; ++i) {
    rho_new[i] = rho[i];
    if (ne.Hpp[i] <= 0) continue;
    const double dfp = dim > 0 ? ne.Hfp.col(static_cast<Eigen::Index>(i)).dot(df) : 0.0;
    rho_new[i] = std::max(1e-4, rho[i] - (ne.bp[i] + dfp) / w.hpp_d[i]);
  }
  return true;
}

// Drops the observations whose pattern does not match any more (occlusion, wrong depth); a point left
// without observations is an outlier. Returns how many observations were dropped; the kept ones' RMS
// residual and count (what cost() reports, from the same residuals) go to *rmse and *count.
int PhotometricBA::removeOutliers(const std::vector<BaFrame>& frames, std::vector<BaPoint>& points,
                                  const std::vector<HostPattern>& gw, double* rmse, int* count) const {
  const PairTransforms pairs(frames);
  std::array<int, kReductionChunks> removed{};
  std::array<CostSums, kReductionChunks> kept{};
  forEachChunk(points.size(), [&](int chunk, std::size_t begin, std::size_t end) {
    Eigen::Matrix<double, 8, 1> r;
    for (std::size_t i = begin; i < end; ++i) {
      BaPoint& p = points[i];
      if (p.outlier) continue;
      std::size_t keep = 0;
      for (int t : p.targets) {
        if (evaluateCore(frames, pairs, p.host, p.u, p.v, p.inv_depth, t, r, nullptr, gw[i].I.data()) &&
            std::sqrt(r.squaredNorm() / 8) <= cfg_.outlier_energy) {
          p.targets[keep++] = t;
          kept[chunk].addPattern(r, gw[i], cfg_.huber);
        } else {
          ++removed[chunk];
        }
      }
      p.targets.resize(keep);
      if (p.targets.empty()) p.outlier = true;
    }
  });
  const CostSums sum = CostSums::total(kept);
  *rmse = sum.rmse();
  *count = sum.n;
  int n = 0;
  for (int k : removed) n += k;
  return n;
}

BaStats PhotometricBA::optimize(std::vector<BaFrame>& frames, std::vector<BaPoint>& points,
                                const BaPrior* prior) const {
  BaStats stats;
  const int F = static_cast<int>(frames.size());
  for (const BaPoint& p : points) {
    if (p.host < 0 || p.host >= F) throw std::out_of_range("photometric BA: point host out of range");
    for (int t : p.targets)
      if (t < 0 || t >= F || t == p.host) throw std::out_of_range("photometric BA: bad point target");
  }
  // Frame parameter index (-1 for fixed frames): the system only holds the free ones.
  std::vector<int> slot(F, -1);
  int nf = 0;
  for (int f = 0; f < F; ++f)
    if (!frames[f].fixed) slot[f] = nf++;
  const int dim = nf * kFrameParams;
  if (prior && prior->empty()) prior = nullptr;
  const std::vector<HostPattern> gw = hostPatterns(frames, points);
  const std::size_t np = points.size();
  std::vector<double> rho(np), rho_new(np);
  for (std::size_t i = 0; i < np; ++i) rho[i] = points[i].inv_depth;

  // Each trial state's cost comes with its normal equations from the same residuals, so that an
  // accepted step needs no second pass over the images; the last iteration's trial needs only its cost.
  NormalEquations ne, ne_try;
  CostSums sums;
  accumulate(frames, points, rho, gw, slot, dim, ne, prior, -1, &sums);
  double c = sums.energy(prior, frames);
  stats.initial_cost = c;
  stats.initial_rmse = sums.rmse();
  stats.residuals = sums.n;
  LmDamping lm(cfg_.lambda_initial, kLambdaFloor);
  StepScratch scratch{Eigen::MatrixXd(dim, dim), Eigen::VectorXd(dim), std::vector<double>(np), {}, {}};
  Eigen::VectorXd df;
  for (int it = 0; it < cfg_.iterations; ++it, ++stats.iterations) {
    if (prior) addPrior(*prior, frames, slot, ne);
    const bool last = it + 1 == cfg_.iterations;
    bool accepted = false;
    for (int tries = 0; tries < 5 && !accepted; ++tries) {
      if (!dampedStep(ne, lm.lambda(), dim, rho, scratch, df, rho_new)) {
        lm.rejected();
        continue;
      }
      std::vector<BaFrame> f_new = frames;
      for (int f = 0; f < F; ++f) {
        if (slot[f] < 0) continue;
        const Eigen::Matrix<double, 8, 1> x = df.segment<8>(slot[f] * 8);
        f_new[f].T_w_c = SE3::exp(x.head<6>()) * frames[f].T_w_c;
        f_new[f].a += x[6];
        f_new[f].b += x[7];
      }
      double c_new;
      if (last) {
        c_new = cost(f_new, points, rho_new, gw, prior, nullptr, nullptr);
      } else {
        accumulate(f_new, points, rho_new, gw, slot, dim, ne_try, prior, -1, &sums);
        c_new = sums.energy(prior, f_new);
      }
      if (c_new < c) {
        frames.swap(f_new);
        rho.swap(rho_new);
        std::swap(ne, ne_try);
        accepted = true;
        const bool converged = c - c_new < 1e-6 * c;
        c = c_new;
        lm.accepted();
        if (converged) it = cfg_.iterations;
      } else {
        lm.rejected();
      }
    }
    if (!accepted) break;
  }
  for (std::size_t i = 0; i < np; ++i) points[i].inv_depth = rho[i];
  stats.outliers_removed = removeOutliers(frames, points, gw, &stats.final_rmse, &stats.residuals);
  return stats;
}

void PhotometricBA::accumulate(const std::vector<BaFrame>& frames, const std::vector<BaPoint>& points,
                               const std::vector<double>& rho, const std::vector<HostPattern>& gw,
                               const std::vector<int>& slot, int dim, NormalEquations& ne,
                               const BaPrior* prior, int only_host, CostSums* sums) const {
  const double d = cfg_.huber;
  const PairTransforms pairs(frames);
  // Without a prior every Jacobian is taken at the current state (lin stays null).
  const bool fej = prior && !prior->empty();
  const std::vector<BaFrame> lin_frames = fej ? linearizationFrames(frames, prior) : std::vector<BaFrame>{};
  const std::optional<PairTransforms> lin_pairs =
      fej ? std::optional<PairTransforms>(lin_frames) : std::nullopt;
  const LinearizationState lin{&lin_frames, fej ? &*lin_pairs : nullptr};
  const auto np = static_cast<Eigen::Index>(points.size());
  ne.Hff = Eigen::MatrixXd::Zero(dim, dim);
  ne.bf = Eigen::VectorXd::Zero(dim);
  ne.Hpp.assign(points.size(), 0.0);
  ne.bp.assign(points.size(), 0.0);
  ne.Hfp.setZero(dim, np);
  // Per chunk: its own sums of every frame pair (added below in chunk order, then expanded into the
  // frame blocks); the point columns are disjoint.
  const int F = pairs.F;
  std::vector<std::vector<PairSums>> pc(kReductionChunks);
  std::array<CostSums, kReductionChunks> part{};
  forEachChunk(points.size(), [&](int chunk, std::size_t begin, std::size_t end) {
    std::vector<PairSums>& ps = pc[chunk];
    ps.assign(static_cast<std::size_t>(F) * F, PairSums{});
    Eigen::Matrix<double, 8, 1> r, w;
    PairJacobian J;
    for (auto i = static_cast<Eigen::Index>(begin); i < static_cast<Eigen::Index>(end); ++i) {
      const BaPoint& p = points[i];
      if (p.outlier || (only_host >= 0 && p.host != only_host)) continue;
      if (p.prior_weight > 0) {
        ne.Hpp[i] += p.prior_weight;
        ne.bp[i] += p.prior_weight * (rho[i] - p.prior_inv_depth);
        if (sums) part[chunk].addPointPrior(p, rho[i]);
      }
      for (int t : p.targets) {
        if (!evaluateCore(frames, pairs, p.host, p.u, p.v, rho[i], t, r, &J, gw[i].I.data(),
                          fej ? &lin : nullptr))
          continue;
        if (sums) part[chunk].addPattern(r, gw[i], d);
        for (int k = 0; k < 8; ++k) w[k] = gw[i].w[k] * huberWeight(r[k], d);
        addResiduals(J, r, w, slot[p.host], slot[t], i, ps[p.host * F + t], ne);
      }
    }
  });
  for (int pi = 0; pi < F * F; ++pi) {
    PairSums total;
    for (int c = 0; c < kReductionChunks; ++c)
      if (!pc[c].empty()) total += pc[c][pi];
    if (total.used) addPairSums(total, slot[pi / F], slot[pi % F], ne);
  }
  if (sums) *sums = CostSums::total(part);
}

void PhotometricBA::denseNormalEquations(const std::vector<BaFrame>& frames,
                                         const std::vector<BaPoint>& points, Eigen::MatrixXd& H,
                                         Eigen::VectorXd& b) const {
  const int F = static_cast<int>(frames.size());
  const auto np = static_cast<Eigen::Index>(points.size());
  std::vector<int> slot(F);
  for (int f = 0; f < F; ++f) slot[f] = f;
  const int dim = F * kFrameParams;
  std::vector<double> rho(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) rho[i] = points[i].inv_depth;
  NormalEquations ne;
  accumulate(frames, points, rho, hostPatterns(frames, points), slot, dim, ne, nullptr);
  H = Eigen::MatrixXd::Zero(dim + np, dim + np);
  b = Eigen::VectorXd::Zero(dim + np);
  H.topLeftCorner(dim, dim) = ne.Hff;
  H.topRightCorner(dim, np) = ne.Hfp;
  H.bottomLeftCorner(np, dim) = ne.Hfp.transpose();
  b.head(dim) = ne.bf;
  for (Eigen::Index i = 0; i < np; ++i) {
    H(dim + i, dim + i) = ne.Hpp[i];
    b(dim + i) = ne.bp[i];
  }
}

}  // namespace eds
