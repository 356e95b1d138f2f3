#include "eval/align.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace eds::eval {

std::string toString(Alignment a) {
  switch (a) {
    case Alignment::kSim3: return "sim3";
    case Alignment::kSe3: return "se3";
    case Alignment::kPosYaw: return "posyaw";
    case Alignment::kNone: return "none";
  }
  return "unknown";
}

Alignment parseAlignment(const std::string& name) {
  if (name == "sim3") return Alignment::kSim3;
  if (name == "se3") return Alignment::kSe3;
  if (name == "posyaw") return Alignment::kPosYaw;
  if (name == "none") return Alignment::kNone;
  throw std::invalid_argument("unknown alignment '" + name + "' (expected sim3, se3, posyaw or none)");
}

double bestYaw(const Mat3& C) {
  const double a = C(0, 1) - C(1, 0);
  const double b = C(0, 0) + C(1, 1);
  return std::numbers::pi / 2 - std::atan2(b, a);
}

Mat3 rotZ(double theta) { return Eigen::AngleAxisd(theta, Vec3::UnitZ()).toRotationMatrix(); }

Sim3 umeyama(const std::vector<Vec3>& gt, const std::vector<Vec3>& est, bool known_scale, bool yaw_only) {
  const std::size_t n = std::min(gt.size(), est.size());
  if (n == 0) throw std::invalid_argument("umeyama: no point pairs");
  Vec3 mu_gt = Vec3::Zero(), mu_est = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mu_gt += gt[i];
    mu_est += est[i];
  }
  mu_gt /= static_cast<double>(n);
  mu_est /= static_cast<double>(n);

  Mat3 C = Mat3::Zero();  // (1/n) sum (gt - mu_gt)(est - mu_est)^T
  double sigma2 = 0.0;    // (1/n) sum |est - mu_est|^2
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 dg = gt[i] - mu_gt;
    const Vec3 de = est[i] - mu_est;
    C += dg * de.transpose();
    sigma2 += de.squaredNorm();
  }
  C /= static_cast<double>(n);
  sigma2 /= static_cast<double>(n);

  const Eigen::JacobiSVD<Mat3> svd(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3& U = svd.matrixU();
  const Mat3& V = svd.matrixV();
  Mat3 S = Mat3::Identity();
  if (U.determinant() * V.determinant() < 0) S(2, 2) = -1;

  Sim3 out;
  // The toolbox's yaw-only variant uses the unnormalized correlation est^T gt (transposed).
  out.R = yaw_only ? rotZ(bestYaw(C.transpose() * static_cast<double>(n))) : Mat3(U * S * V.transpose());
  if (!known_scale) {
    if (!(sigma2 > 0.0)) throw std::invalid_argument("sim3 alignment: estimated positions do not move");
    out.s = (svd.singularValues().asDiagonal() * S).trace() / sigma2;
  }
  out.t = mu_gt - out.s * (out.R * mu_est);
  return out;
}

Sim3 alignTrajectory(const std::vector<Vec3>& p_gt, const std::vector<Quat>& q_gt,
                     const std::vector<Vec3>& p_est, const std::vector<Quat>& q_est, Alignment method,
                     int frames) {
  if (method == Alignment::kNone) return {};
  const std::size_t total = std::min(p_gt.size(), p_est.size());
  if (total == 0) throw std::invalid_argument("alignment: no matched poses");
  if (frames == 0 || frames < -1)
    throw std::invalid_argument("alignment: frames must be -1 (all) or positive, got " +
                                std::to_string(frames));
  const std::size_t k = frames == -1 ? total : std::min<std::size_t>(total, frames);
  const std::vector<Vec3> gt(p_gt.begin(), p_gt.begin() + k);
  const std::vector<Vec3> est(p_est.begin(), p_est.begin() + k);

  Sim3 out;
  switch (method) {
    case Alignment::kSim3:
      if (frames != -1 && frames < 2) throw std::invalid_argument("sim3 alignment needs at least 2 frames");
      return umeyama(gt, est, false, false);
    case Alignment::kSe3:
      if (frames == 1) {
        out.R = q_gt[0].toRotationMatrix() * q_est[0].toRotationMatrix().transpose();
        out.t = p_gt[0] - out.R * p_est[0];
        return out;
      }
      return umeyama(gt, est, true, false);
    case Alignment::kPosYaw:
      if (frames == 1) {
        const Mat3 C_R = q_est[0].toRotationMatrix() * q_gt[0].toRotationMatrix().transpose();
        out.R = rotZ(bestYaw(C_R));
        out.t = p_gt[0] - out.R * p_est[0];
        return out;
      }
      return umeyama(gt, est, true, true);
    case Alignment::kNone: break;
  }
  return out;
}

Trajectory applySim3(const Trajectory& traj, const Sim3& T) {
  Trajectory out;
  out.reserve(traj.size());
  for (const StampedPose& p : traj)
    out.push_back({p.t, SE3(SO3(T.R) * p.T_w_c.so3(), T.apply(p.T_w_c.translation()))});
  return out;
}

}  // namespace eds::eval
