#pragma once
// Event generation model prediction (paper Eqs. 3-6): ΔL̂(u) = -∇L̂(u) · J(u, Z) · ν Δt.
//
// Units: the gradient ∇L̂ is per pixel (Sobel / 8 on the undistorted keyframe image), while the
// feature sensitivity matrix J of Eq. 5 maps the camera twist ν = (v, ω) to a velocity on the
// *normalized* image plane. We scale J's rows by fx and fy so both are in pixels (the authors' code
// dots the pixel gradient with the normalized-plane flow, which weighs x and y flow equally only when
// fx = fy, and changes the effective Huber scale with the focal length).
//
// With Δt and the scale of ν removed by the normalization in the tracker, each point contributes a
// fixed row a = -(gx fx J_1 + gy fy J_2) so that ΔL̂ ∝ a · ν.
#include <Eigen/Core>

#include "core/camera.hpp"

namespace eds {

using Row6 = Eigen::Matrix<double, 1, 6>;

// J(u, Z) of Eq. 5 at normalized coordinates (x, y) and depth Z; columns (vx vy vz ωx ωy ωz).
inline Eigen::Matrix<double, 2, 6> featureSensitivity(double x, double y, double Z) {
  Eigen::Matrix<double, 2, 6> J;
  const double iz = 1.0 / Z;
  J << -iz, 0, x * iz, x * y, -(1 + x * x), y,  //
      0, -iz, y * iz, 1 + y * y, -x * y, -x;
  return J;
}

// The row a with ΔL̂ = a · ν Δt for a keyframe pixel (u, v) with log gradient (gx, gy) and inverse depth.
inline Row6 egmRow(const CameraModel& pinhole, double u, double v, double gx, double gy, double inv_depth) {
  const Vec3 ray = pinhole.pinholeRay(u, v);
  const Eigen::Matrix<double, 2, 6> J = featureSensitivity(ray.x(), ray.y(), 1.0 / inv_depth);
  return -(gx * pinhole.fx * J.row(0) + gy * pinhole.fy * J.row(1));
}

}  // namespace eds
