#pragma once
// What a report shows of one run: an `eds run` output folder (summary, trajectories, timings, map,
// keyframes, event-frame snapshots), or a bare TUM trajectory of another system, and its accuracy
// against ground truth when there is one.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "eval/ate.hpp"
#include "eval/rpe.hpp"
#include "io/ply.hpp"
#include "io/trajectory_io.hpp"
#include "system/odometry.hpp"

namespace eds::report {

struct RunData {
  std::filesystem::path dir;  // the folder, or the TUM file
  std::string name;           // label in plots and tables
  bool is_run = false;        // an `eds run` folder (else a bare trajectory)
  nlohmann::json summary, timings;
  Trajectory events, frames, keyframes;  // final poses; `frames` holds a bare trajectory
  // Where new map segments begin in `events` and `frames` (their "# segment" lines; none: one map).
  std::vector<std::size_t> event_segments, frame_segments;
  PointCloud map;
  std::vector<EventFrameSnapshot> snapshots;
};

// An `eds run` folder (InputError naming what is missing when it is not one), or a TUM file.
RunData loadRun(const std::filesystem::path& path);

// Accuracy of one trajectory against the ground truth (sim3, eds eval's conventions).
struct TrajectoryEval {
  std::string label;  // "event-rate poses", "frame poses"
  Trajectory est;     // as estimated
  eval::AteResult ate;
  std::vector<eval::RpeResult> rpe;
};

// The run's trajectories evaluated, the first (event-rate poses when there are any) giving the
// alignment everything else is drawn in. Trajectories that match no ground truth are left out.
std::vector<TrajectoryEval> evaluateRun(const RunData& run, const Trajectory& gt);

// The ground truth for a run: `gt_file` if given, else the run's own groundtruth.txt, else none.
std::optional<Trajectory> findGroundTruth(const RunData& run, const std::filesystem::path& gt_file);

}  // namespace eds::report
