#pragma once
// Absolute trajectory error (ATE) and coverage of an estimate against ground truth, reproducing
// rpg_trajectory_evaluation (DESIGN.md section 5).
#include <cstddef>
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "eval/align.hpp"
#include "eval/associate.hpp"
#include "io/trajectory_io.hpp"

namespace eds::eval {

struct EvalConfig {
  Alignment alignment = Alignment::kSim3;  // sim3 is the default for monocular odometry
  int align_frames = -1;                   // align over the first K matched poses; -1 = all
  TimeNs max_dt = 20'000'000;              // association limit (strict <), 20 ms
  std::optional<TimeWindow> window;        // filter on the ground-truth stamp
  TimeNs max_coverage_gap = 500'000'000;   // longer gaps between matched estimates are not covered
};

// Statistics as the toolbox's compute_statistics: numpy median, population std.
struct ErrorStats {
  double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0;
  std::size_t num_samples = 0;
};
ErrorStats computeStats(const std::vector<double>& values);
// {rmse, mean, median, std, min, max, num_samples}.
nlohmann::json toJson(const ErrorStats& s);

struct AteResult {
  Alignment alignment = Alignment::kSim3;
  int align_frames = -1;
  Sim3 transform;  // gt = s R est + t (the first segment's)
  // An estimate of several map segments: each is aligned on its own. segment_starts: the estimate
  // index where segments 1, 2, ... begin; segment_transforms: one per segment (the identity for a
  // segment with too few matched poses to align, whose poses are then left out of the errors).
  std::vector<MatchedPair> pairs;      // after the window filter, sorted by estimate time
  std::vector<double> trans_errors;    // metres, one per pair
  std::vector<double> rot_errors_deg;  // degrees, one per pair
  ErrorStats trans;
  ErrorStats rot;
  // The rotation errors against the best constant rotation of each segment (the chordal mean of
  // R_gt R_estᵀ) instead of the alignment's, which the positions alone determine: on a path short against
  // its position errors that rotation is poorly determined and dominates `rot`; this one is not.
  std::vector<double> rot_oriented_errors_deg;
  ErrorStats rot_oriented;
  double coverage = 0.0;  // fraction of the ground-truth time span covered, in [0, 1]
  // RMS distance (m) of the ground-truth positions the (first segment's) alignment was fitted to from
  // their principal axis. A rotation about
  // that axis moves them by about this much, so against a larger position error the positions leave it
  // free: see rotationFreeAboutPath().
  double path_off_axis_m = 0.0;
  std::vector<std::size_t> segment_starts;
  std::vector<Sim3> segment_transforms;
};

// Whether the alignment (sim3, se3 over more than one pose) fits its rotation about the path's axis to
// the position errors
// rather than to the path: the position RMSE exceeds a tenth of path_off_axis_m, so that turning the
// alignment by a tenth of a radian (6 degrees) about the axis moves the positions by less than their
// error (on a straight rail it is free up to a half turn). The rotation errors through the alignment
// (`rot`) then mean little; `rot_oriented` is not affected.
bool rotationFreeAboutPath(const AteResult& r);

// The estimate in the ground truth's frame, each segment through its own transform.
Trajectory alignedEstimate(const Trajectory& est, const AteResult& r);

// Covered time / gt span (DESIGN.md section 5). The span runs from the first to the last gt stamp,
// clipped to the window if given; covered time sums the intervals between consecutive matched
// estimate stamps that are at most max_gap apart (also clipped to the span).
double computeCoverage(const Trajectory& est, const Trajectory& gt, const std::vector<MatchedPair>& pairs,
                       const std::optional<TimeWindow>& window, TimeNs max_gap);

// Associates, filters, aligns and measures. Throws std::invalid_argument when nothing matches or the
// alignment is impossible; callers that know the file names turn that into an InputError.
// `segment_starts`: where the estimate's map segments 1, 2, ... begin (none: one segment).
AteResult evaluateAte(const Trajectory& est, const Trajectory& gt, const EvalConfig& cfg,
                      const std::vector<std::size_t>& segment_starts = {});
// Same on pairs already associated and filtered (sorted by estimate time).
AteResult evaluateAtePairs(const Trajectory& est, const Trajectory& gt, std::vector<MatchedPair> pairs,
                           const EvalConfig& cfg, const std::vector<std::size_t>& segment_starts = {});

// Both trajectories with the files they came from, so errors can name them.
struct EvalInputs {
  std::filesystem::path gt_file, est_file;
  Trajectory gt, est;
  std::vector<std::size_t> est_segment_starts;  // from the estimate's "# segment" lines
};
// Reads both TUM files (unsorted stamps allowed, as in the toolbox); empty files are InputErrors.
EvalInputs readEvalInputs(const std::filesystem::path& gt_file, const std::filesystem::path& est_file);
// evaluateAte with errors as InputErrors naming both files (zero matched pairs, none in the window).
AteResult evaluateAte(const EvalInputs& in, const EvalConfig& cfg);
AteResult evaluateAteFiles(const std::filesystem::path& gt_file, const std::filesystem::path& est_file,
                           const EvalConfig& cfg);

// JSON with trans.{rmse,mean,median,std,min,max,num_samples} (m), rot.{...} (deg), rot_oriented.{...}
// (deg), matched_pairs, coverage, alignment, align_frames, scale, segments, path_off_axis_m and
// alignment_rotation_free.
nlohmann::json toJson(const AteResult& r);
void writeJson(const std::filesystem::path& file, const AteResult& r);
void writeJson(const std::filesystem::path& file, const nlohmann::json& j);

}  // namespace eds::eval
