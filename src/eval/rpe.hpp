#pragma once
// Relative pose error as rpg_trajectory_evaluation computes it: for sub-trajectories of fixed
// ground-truth path length (by default 10..50 % of the total), the error of the estimated relative
// motion between a pose and the one `distance` metres further along the ground truth.
#include <string>
#include <vector>

#include "eval/ate.hpp"

namespace eds::eval {

struct RpeConfig {
  std::vector<double> length_fractions = {0.1, 0.2, 0.3, 0.4, 0.5};
  double max_length_diff_ratio = 0.2;  // an end pose must be this close (relative) to the length
};

struct RpeResult {
  double distance = 0;    // sub-trajectory length in metres (truncated to cm, as the toolbox does)
  ErrorStats trans;       // metres
  ErrorStats trans_perc;  // percent of distance
  ErrorStats rot;         // degrees
  ErrorStats yaw;         // degrees, |yaw| of the error
  ErrorStats gravity;     // degrees, roll and pitch of the error combined
  ErrorStats rot_deg_per_m;
};

// Uses the ATE result's matched (and window-filtered) pairs and its alignment scale; the total
// length is that of the raw ground truth inside the window. Lengths with fewer than 2 comparisons
// give empty statistics (num_samples 0).
std::vector<RpeResult> evaluateRpe(const Trajectory& est, const Trajectory& gt, const AteResult& ate,
                                   const EvalConfig& cfg, const RpeConfig& rpe = {});

// [{distance, trans, trans_perc, rot, yaw, gravity, rot_deg_per_m}, ...] with statistics objects.
nlohmann::json toJson(const std::vector<RpeResult>& results);

// The toolbox's file-name form of a distance: "%3.1f" with '.' replaced by '_' (8.0 -> "8_0").
std::string rpeDistanceTag(double distance);

}  // namespace eds::eval
