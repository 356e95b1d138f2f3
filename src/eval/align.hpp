#pragma once
// Trajectory alignment gt = s * R * est + t with the conventions of rpg_trajectory_evaluation
// (align_utils / align_trajectory), so that errors reproduce the toolbox's published numbers.
#include <string>
#include <vector>

#include "core/se3.hpp"
#include "io/trajectory_io.hpp"

namespace eds::eval {

enum class Alignment { kSim3, kSe3, kPosYaw, kNone };

// "sim3", "se3", "posyaw", "none".
std::string toString(Alignment a);
// Throws std::invalid_argument for an unknown name.
Alignment parseAlignment(const std::string& name);

struct Sim3 {
  double s = 1.0;
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  Vec3 apply(const Vec3& p) const { return s * (R * p) + t; }
};

// Umeyama on paired positions, gt_i ~ s R est_i + t. The means and the correlation use all the given
// pairs. known_scale fixes s = 1; yaw_only restricts R to a rotation about z.
Sim3 umeyama(const std::vector<Vec3>& gt, const std::vector<Vec3>& est, bool known_scale, bool yaw_only);

// The yaw theta maximizing trace(Rz(theta) C).
double bestYaw(const Mat3& C);
Mat3 rotZ(double theta);

// The trajectory moved into the aligned frame: positions s R p + t, orientations R R_w_c (for plots
// and error-over-time studies; `eds eval --aligned`).
Trajectory applySim3(const Trajectory& traj, const Sim3& T);

// Aligns over the first `frames` pairs (-1: all). se3 and posyaw with frames == 1 use the first pose's
// orientation as well. Throws std::invalid_argument for sim3 with fewer than 2 frames, for frames == 0
// or < -1, for an empty input, and when positions are degenerate for sim3 (no spread).
Sim3 alignTrajectory(const std::vector<Vec3>& p_gt, const std::vector<Quat>& q_gt,
                     const std::vector<Vec3>& p_est, const std::vector<Quat>& q_est, Alignment method,
                     int frames);

}  // namespace eds::eval
