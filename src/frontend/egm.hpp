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
#include "core/se3.hpp"

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

// The same row for the keyframe point seen from a camera at T_c_kf, with ν that camera's velocity
// expressed in the keyframe's axes (the convention of the row above): the gradient is carried into the
// camera's pixels through the warp's Jacobian (locally fronto-parallel in the keyframe, as the
// tracker's constant inverse depth per pixel assumes), the flow is the camera's own, and ν is turned
// into the camera's axes. At T_c_kf = identity it is egmRow; far from the keyframe the keyframe's own
// flow field is no longer the camera's, and this keeps the prediction where the events are.
inline Row6 egmRowAtView(const CameraModel& pinhole, double u, double v, double gx, double gy,
                         double inv_depth, const SE3& T_c_kf) {
  const Mat3 R = T_c_kf.rotationMatrix();
  const Vec3 q = R * (pinhole.pinholeRay(u, v) / inv_depth) + T_c_kf.translation();
  const double iz = 1.0 / q.z();
  Eigen::Matrix<double, 2, 3> du_dq;
  du_dq << pinhole.fx * iz, 0, -pinhole.fx * q.x() * iz * iz, 0, pinhole.fy * iz,
      -pinhole.fy * q.y() * iz * iz;
  Eigen::Matrix<double, 3, 2> dq_dukf;
  dq_dukf.col(0) = R.col(0) / (pinhole.fx * inv_depth);
  dq_dukf.col(1) = R.col(1) / (pinhole.fy * inv_depth);
  const Eigen::Matrix2d M = du_dq * dq_dukf;  // ∂u_c / ∂u_kf
  const Eigen::RowVector2d g = Eigen::RowVector2d(gx, gy) * M.inverse();
  const Eigen::Matrix<double, 2, 6> J = featureSensitivity(q.x() * iz, q.y() * iz, q.z());
  Row6 a = -(g.x() * pinhole.fx * J.row(0) + g.y() * pinhole.fy * J.row(1));
  // ν_c = blockdiag(R, R) ν_kf.
  Row6 out;
  out.head<3>() = a.head<3>() * R;
  out.tail<3>() = a.tail<3>() * R;
  return out;
}

}  // namespace eds
