// The Gaussian prior of the photometric bundle adjustment (photometric_ba.hpp): its energy at a state.
#include <stdexcept>

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

}  // namespace eds
