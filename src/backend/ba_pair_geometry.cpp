#include "backend/ba_pair_geometry.hpp"

#include <cmath>

namespace eds {

PairTransforms::PairTransforms(const std::vector<BaFrame>& frames) : F(static_cast<int>(frames.size())) {
  T_t_h.resize(F * F), R_t_h.resize(F * F), R_t_w.resize(F * F), e.resize(F * F);
  R_w_c.resize(F), t_w_c.resize(F);
  for (int t = 0; t < F; ++t) {
    R_w_c[t] = frames[t].T_w_c.rotationMatrix();
    t_w_c[t] = frames[t].T_w_c.translation();
    const SE3 T_t_w = frames[t].T_w_c.inverse();
    const Mat3 Rtw = T_t_w.rotationMatrix();
    for (int h = 0; h < F; ++h) {
      const int i = h * F + t;
      T_t_h[i] = T_t_w * frames[h].T_w_c;
      R_t_h[i] = T_t_h[i].rotationMatrix();
      R_t_w[i] = Rtw;
      e[i] = std::exp(frames[t].a - frames[h].a);
    }
  }
}

void pairJacobian(const CameraModel& cam, const std::vector<BaFrame>& frames, const PairTransforms& pairs,
                  int host, int target, const Vec3& x_c, double inv_rho, const PatternGeometry& pg,
                  PairJacobian& J, const LinearizationState* lin) {
  const int pi = host * pairs.F + target;
  const PairTransforms& G = lin ? *lin->pairs : pairs;
  const BaFrame& Hg = lin ? (*lin->frames)[host] : frames[host];
  const Arr8 du = Eigen::Map<const Arr8>(kPatternU), dv = Eigen::Map<const Arr8>(kPatternV);
  Arr8 RXg[3], Xg[3], izg;
  if (lin) {
    const Mat3& Rg = G.R_t_h[pi];
    const Vec3 Gx_c = Rg * x_c, G_du = Rg.col(0) / cam.fx, G_dv = Rg.col(1) / cam.fy;
    const Vec3 tg = G.T_t_h[pi].translation();
    for (int c = 0; c < 3; ++c) {
      RXg[c] = Gx_c[c] + du * G_du[c] + dv * G_dv[c];
      Xg[c] = RXg[c] * inv_rho + tg[c];
    }
    izg = (Xg[2] > 1e-6).select(Xg[2].inverse(), pg.iz);
  }
  const Arr8* RX = lin ? RXg : pg.RX;
  const Arr8* X = lin ? Xg : pg.X;
  const Arr8& iz = lin ? izg : pg.iz;
  const Arr8 dIx = pg.dx * cam.fx * iz, dIy = pg.dy * cam.fy * iz;
  const Arr8 dIz = -(pg.dx * cam.fx * X[0] + pg.dy * cam.fy * X[1]) * iz * iz;
  // g = ∂I/∂X_t R_t_w; the point in the world X_w from the host's pose like X_t from the pair's.
  const Mat3& Rtw = G.R_t_w[pi];
  const Mat3& Rw = G.R_w_c[host];
  const Vec3 Wx_c = Rw * x_c, W_du = Rw.col(0) / cam.fx, W_dv = Rw.col(1) / cam.fy;
  Arr8 g[3], Xw[3];
  for (int c = 0; c < 3; ++c) {
    g[c] = dIx * Rtw(0, c) + dIy * Rtw(1, c) + dIz * Rtw(2, c);
    Xw[c] = (Wx_c[c] + du * W_du[c] + dv * W_dv[c]) * inv_rho + G.t_w_c[host][c];
  }
  // X_t = T_w_t^-1 X_w: a left perturbation of the target moves X_t by -R_t_w (δv + δω x X_w),
  // one of the host moves X_w by (δv + δω x X_w).
  for (int c = 0; c < 3; ++c) J.A.col(c) = g[c].matrix();
  J.A.col(3) = (Xw[1] * g[2] - Xw[2] * g[1]).matrix();
  J.A.col(4) = (Xw[2] * g[0] - Xw[0] * g[2]).matrix();
  J.A.col(5) = (Xw[0] * g[1] - Xw[1] * g[0]).matrix();
  const double eg = G.e[pi];
  J.A.col(6) = (eg * (pg.I_h - Hg.b)).matrix();
  // X = R_t_h x_h / ρ + t_t_h.
  J.d_rho = (-(dIx * RX[0] + dIy * RX[1] + dIz * RX[2]) * (inv_rho * inv_rho)).matrix();
  J.e = eg;
}
}  // namespace eds
