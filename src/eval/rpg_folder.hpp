#pragma once
// rpg_trajectory_evaluation result folders: stamped_groundtruth.txt, stamped_traj_estimate.txt,
// optional eval_cfg.yaml (align_type, align_num_frames) and start_end_time.yaml (start_time_sec,
// end_time_sec, either may be absent).
#include <filesystem>

#include "eval/ate.hpp"

namespace eds::eval {

inline constexpr const char* kRpgGroundTruthFile = "stamped_groundtruth.txt";
inline constexpr const char* kRpgEstimateFile = "stamped_traj_estimate.txt";
inline constexpr const char* kRpgEvalCfgFile = "eval_cfg.yaml";
inline constexpr const char* kRpgTimeWindowFile = "start_end_time.yaml";

// Applies eval_cfg.yaml to cfg (alignment and frames); a missing file leaves cfg unchanged. Throws
// InputError naming the file for unreadable yaml, an unknown align_type or a bad frame count.
void applyEvalCfgYaml(const std::filesystem::path& file, EvalConfig& cfg);

// Reads start_end_time.yaml; a missing key means unbounded on that side. Throws InputError naming
// the file when it cannot be read or parsed, or when start > end.
TimeWindow readTimeWindowYaml(const std::filesystem::path& file);

// The folder's configuration: sim3 over all poses unless eval_cfg.yaml says otherwise, plus the
// window of start_end_time.yaml when present.
EvalConfig loadRpgConfig(const std::filesystem::path& dir);

// loadRpgConfig + evaluateAteFiles on the folder's two trajectories.
AteResult evaluateRpgFolder(const std::filesystem::path& dir);

}  // namespace eds::eval
