// The Gaussian prior of the photometric bundle adjustment (photometric_ba.hpp): its energy at a state,
// and how the marginalization of a keyframe makes it.
#include <Eigen/Cholesky>
#include <stdexcept>

#include "backend/normal_equations.hpp"
#include "backend/photometric_ba.hpp"

namespace eds {

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
  std::vector<double> rho(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) rho[i] = points[i].inv_depth;
  accumulate(frames, points, rho, hostPatterns(frames, points), slot, dim, ne, prior, m);
  // The residuals are linearized at the current state, their Jacobians at the linearization point
  // x0 (first estimates): r(x) ≈ r + J (δ − δ_now), with δ = x ⊟ x0. In terms of δ the gradient is
  // Jᵀr − JᵀJ δ_now; δ_now is zero except for the frames the old prior already holds at their x0.
  Eigen::VectorXd d_now = Eigen::VectorXd::Zero(dim);
  if (prior && !prior->empty()) {
    const Eigen::VectorXd dp = prior->delta(frames);
    for (std::size_t i = 0; i < prior->frames.size(); ++i)
      d_now.segment<8>(8 * prior->frames[i]) = dp.segment<8>(8 * i);
  }
  ne.bf.noalias() -= ne.Hff * d_now;
  for (std::size_t i = 0; i < points.size(); ++i)
    ne.bp[i] -= ne.Hfp.col(static_cast<Eigen::Index>(i)).dot(d_now);
  Eigen::MatrixXd H = ne.Hff;
  Eigen::VectorXd b = ne.bf;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (ne.Hpp[i] <= 1e-12) continue;
    const auto col = ne.Hfp.col(static_cast<Eigen::Index>(i));
    H.noalias() -= col * col.transpose() / ne.Hpp[i];
    b.noalias() -= col * (ne.bp[i] / ne.Hpp[i]);
  }
  // The old prior joins as it is: same variables, same linearization points (never relinearized).
  std::vector<int> in_prior(F, -1);
  if (prior && !prior->empty()) {
    const int np = static_cast<int>(prior->frames.size());
    for (int i = 0; i < np; ++i) {
      const int si = prior->frames[i];
      in_prior[si] = i;
      b.segment<8>(si * 8) += prior->b.segment<8>(8 * i);
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
    const int i = in_prior[f];
    out.T0.push_back(i >= 0 ? prior->T0[i] : frames[f].T_w_c);
    out.a0.push_back(i >= 0 ? prior->a0[i] : frames[f].a);
    out.b0.push_back(i >= 0 ? prior->b0[i] : frames[f].b);
  }
  return out;
}

}  // namespace eds
