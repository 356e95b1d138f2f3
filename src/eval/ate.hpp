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
  Sim3 transform;                      // gt = s R est + t
  std::vector<MatchedPair> pairs;      // after the window filter, sorted by estimate time
  std::vector<double> trans_errors;    // metres, one per pair
  std::vector<double> rot_errors_deg;  // degrees, one per pair
  ErrorStats trans;
  ErrorStats rot;
  double coverage = 0.0;  // fraction of the ground-truth time span covered, in [0, 1]
};

// Covered time / gt span (DESIGN.md section 5). The span runs from the first to the last gt stamp,
// clipped to the window if given; covered time sums the intervals between consecutive matched
// estimate stamps that are at most max_gap apart (also clipped to the span).
double computeCoverage(const Trajectory& est, const Trajectory& gt, const std::vector<MatchedPair>& pairs,
                       const std::optional<TimeWindow>& window, TimeNs max_gap);

// Associates, filters, aligns and measures. Throws std::invalid_argument when nothing matches or the
// alignment is impossible; callers that know the file names turn that into an InputError.
AteResult evaluateAte(const Trajectory& est, const Trajectory& gt, const EvalConfig& cfg);
// Same on pairs already associated and filtered (sorted by estimate time).
AteResult evaluateAtePairs(const Trajectory& est, const Trajectory& gt, std::vector<MatchedPair> pairs,
                           const EvalConfig& cfg);

// Both trajectories with the files they came from, so errors can name them.
struct EvalInputs {
  std::filesystem::path gt_file, est_file;
  Trajectory gt, est;
};
// Reads both TUM files (unsorted stamps allowed, as in the toolbox); empty files are InputErrors.
EvalInputs readEvalInputs(const std::filesystem::path& gt_file, const std::filesystem::path& est_file);
// evaluateAte with errors as InputErrors naming both files (zero matched pairs, none in the window).
AteResult evaluateAte(const EvalInputs& in, const EvalConfig& cfg);
AteResult evaluateAteFiles(const std::filesystem::path& gt_file, const std::filesystem::path& est_file,
                           const EvalConfig& cfg);

// JSON with trans.{rmse,mean,median,std,min,max,num_samples} (m), rot.{...} (deg), matched_pairs,
// coverage, alignment, align_frames and scale.
nlohmann::json toJson(const AteResult& r);
void writeJson(const std::filesystem::path& file, const AteResult& r);
void writeJson(const std::filesystem::path& file, const nlohmann::json& j);

}  // namespace eds::eval
