#pragma once
// The report's plots of runs: trajectories from above and from the side, errors over time, stage
// timings, and the data of the 3D view.
#include <string>
#include <vector>

#include "report/run_data.hpp"

namespace eds::report {

// A trajectory to draw, already in the frame (and scale) it is shown in.
struct PathToDraw {
  std::string label, color;
  Trajectory poses;
  bool dashed = false;
};

// Top and side views: the plane of the two largest extents (of the first path, usually the ground
// truth) and the plane of the largest and the smallest.
std::string trajectoryPlots(const std::vector<PathToDraw>& paths);

// Translation (cm) and rotation (deg) error of each evaluated trajectory over time (s from t0).
struct ErrorsToDraw {
  std::string label, color;
  const TrajectoryEval* eval = nullptr;
};
std::string errorPlots(const std::vector<ErrorsToDraw>& errors, const Trajectory& gt, TimeNs t0);

// Box plots of each stage's time per item (timings.json); empty when the run has none.
std::string timingPlot(const RunData& run);

// JSON for view3d.js: the map points (at most `max_points`, thinned evenly) and keyframe positions
// mapped by `align`, the paths, and the world's up direction.
std::string view3dData(const RunData& run, const eval::Sim3& align, const std::vector<PathToDraw>& paths,
                       const Vec3& up, std::size_t max_points = 30000);

// Colours of the report: event-rate poses, frame poses, ground truth, and the i-th run of a comparison.
inline constexpr const char* kEventsColour = "#d62728";
inline constexpr const char* kFramesColour = "#1f77b4";
inline constexpr const char* kGtColour = "#333333";
const char* runColour(std::size_t i);

}  // namespace eds::report
