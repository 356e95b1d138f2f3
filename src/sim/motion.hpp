#pragma once
// Camera motion for the simulator: a trajectory sampled at any time (linear position, slerp
// rotation between samples), from a TUM/ECD file (optionally Gaussian-smoothed) or built in.
#include <filesystem>

#include "io/trajectory_io.hpp"

namespace eds::sim {

class Motion {
 public:
  explicit Motion(Trajectory samples);  // sorted, >= 2 samples; throws std::invalid_argument
  // T_w_c at time t, clamped to the span.
  SE3 pose(TimeNs t) const;
  TimeNs start() const { return samples_.front().t; }
  TimeNs end() const { return samples_.back().t; }
  const Trajectory& samples() const { return samples_; }

 private:
  Trajectory samples_;
};

// Gaussian smoothing in time (sigma in seconds) of positions and rotations (rotations averaged in
// the tangent space of each sample's neighbourhood). Removes mocap jitter that makes spurious events.
Trajectory smoothTrajectory(const Trajectory& traj, double sigma_s);

// Cuts [t_start, t_start + duration] out of a trajectory and shifts time so it starts at 0.
// Throws InputError (naming `source`) if the trajectory is shorter than asked.
Trajectory cutTrajectory(const Trajectory& traj, double t_start_s, double duration_s,
                         const std::string& source);

// A built-in hand-held-like motion: smooth, mostly rotational shake with slow translation, starting at
// the origin looking along +z (camera axes), lively enough for ~1 M events/s in the room preset.
Trajectory handheldMotion(double duration_s, std::uint64_t seed, double rate_hz = 1000.0);

}  // namespace eds::sim
