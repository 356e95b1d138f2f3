// `eds eval`: absolute trajectory error and coverage of an estimate against ground truth, with the
// conventions of rpg_trajectory_evaluation (DESIGN.md section 5).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "core/error.hpp"
#include "eval/ate.hpp"
#include "eval/rpe.hpp"
#include "eval/rpg_folder.hpp"
#include "io/trajectory_io.hpp"

namespace eds::app {
namespace {

struct EvalOptions {
  std::string gt, est, dir, align, time_window, json, aligned;
  int align_frames = -1;
  bool align_frames_given = false;
  bool rpe = false;
  bool interpolate_gt = false;
};

// Ground-truth samples further apart than this are not interpolated between.
constexpr TimeNs kMaxInterpolationBracket = 50'000'000;

void printStatsRow(const char* name, const eval::ErrorStats& s, double factor, const char* unit) {
  std::printf("  %-12s %10.4f %10.4f %10.4f %10.4f  %s\n", name, s.rmse * factor, s.mean * factor,
              s.median * factor, s.max * factor, unit);
}

// The median time between a pose and the ground-truth stamp it is paired with (no interpolation): an
// error the estimate does not make, of about speed x this offset.
double medianPairOffsetMs(const eval::EvalInputs& in, const eval::AteResult& r) {
  std::vector<double> dt;
  dt.reserve(r.pairs.size());
  for (const eval::MatchedPair& p : r.pairs)
    dt.push_back(std::abs(toSeconds(in.est[p.est].t - in.gt[p.gt].t)));
  return 1000 * eval::computeStats(dt).median;
}

void printReport(const EvalOptions& o, const eval::AteResult& r, double median_offset_ms) {
  std::printf("ground truth : %s\n", o.gt.c_str());
  std::printf("estimate     : %s\n", o.est.c_str());
  std::printf("alignment    : %s over %s, scale %.6f\n", eval::toString(r.alignment).c_str(),
              r.align_frames == -1 ? "all poses" : (std::to_string(r.align_frames) + " poses").c_str(),
              r.transform.s);
  if (r.segment_transforms.size() > 1)
    std::printf("map segments : %zu, each aligned on its own\n", r.segment_transforms.size());
  std::printf("matched pairs: %zu (median time to its ground-truth stamp %.2f ms)\n", r.pairs.size(),
              median_offset_ms);
  std::printf("coverage     : %.1f %%\n", 100.0 * r.coverage);
  std::printf("  %-12s %10s %10s %10s %10s\n", "", "rmse", "mean", "median", "max");
  printStatsRow("translation", r.trans, 1.0, "m");
  printStatsRow("translation", r.trans, 100.0, "cm");
  printStatsRow("rotation", r.rot, 1.0, "deg");
  // Not ending in "deg": scripts that take the rotation row by its unit keep taking the one above.
  printStatsRow("rotation", r.rot_oriented, 1.0, "deg, orientations aligned");
  if (eval::rotationFreeAboutPath(r))
    std::printf(
        "note         : the path lies %.4f m (RMS) off a straight line, against a position error of\n"
        "               %.4f m:"
        " the alignment's rotation about that line follows the errors, so the first\n"
        "               rotation row can be off by far more than the tracking was (up to a half turn);\n"
        "               the second is not\n",
        r.path_off_axis_m, r.trans.rmse);
}

void printRpe(const std::vector<eval::RpeResult>& rpe) {
  std::printf("relative error (sub-trajectories by ground-truth path length):\n");
  std::printf("  %10s %6s %12s %10s %12s %12s\n", "length m", "n", "trans rmse m", "trans %", "rot rmse deg",
              "yaw rmse deg");
  for (const eval::RpeResult& r : rpe)
    std::printf("  %10.2f %6zu %12.4f %10.2f %12.4f %12.4f\n", r.distance, r.trans.num_samples, r.trans.rmse,
                r.trans_perc.rmse, r.rot.rmse, r.yaw.rmse);
}

void runEval(EvalOptions o) {
  eval::EvalConfig cfg;
  if (!o.dir.empty()) {
    const std::filesystem::path dir(o.dir);
    cfg = eval::loadRpgConfig(dir);
    if (o.gt.empty()) o.gt = (dir / eval::kRpgGroundTruthFile).string();
    if (o.est.empty()) o.est = (dir / eval::kRpgEstimateFile).string();
  }
  // Explicit options override the folder's configuration.
  if (!o.align.empty()) cfg.alignment = eval::parseAlignment(o.align);
  if (o.align_frames_given) cfg.align_frames = o.align_frames;
  if (!o.time_window.empty()) cfg.window = eval::readTimeWindowYaml(o.time_window);

  eval::EvalInputs in = eval::readEvalInputs(o.gt, o.est);
  if (o.interpolate_gt) in.gt = eval::interpolatedAtStamps(in.gt, in.est, kMaxInterpolationBracket);
  const eval::AteResult r = eval::evaluateAte(in, cfg);
  printReport(o, r, medianPairOffsetMs(in, r));
  nlohmann::json j = eval::toJson(r);
  j["ground_truth_interpolated"] = o.interpolate_gt;
  if (o.rpe) {
    const std::vector<eval::RpeResult> rpe = eval::evaluateRpe(in.est, in.gt, r, cfg);
    printRpe(rpe);
    j["rpe"] = eval::toJson(rpe);
  }
  if (!o.json.empty()) eval::writeJson(o.json, j);
  // The whole estimate in the ground truth's frame and scale.
  if (!o.aligned.empty()) writeTum(o.aligned, eval::alignedEstimate(in.est, r), r.segment_starts);
}

}  // namespace

void addEvalCommand(CLI::App& app) {
  auto opts = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand(
      "eval", "Absolute trajectory error (rpg_trajectory_evaluation conventions) and coverage");
  auto* gt = cmd->add_option("--gt", opts->gt, "ground-truth trajectory (TUM)")->check(CLI::ExistingFile);
  auto* est = cmd->add_option("--est", opts->est, "estimated trajectory (TUM)")->check(CLI::ExistingFile);
  auto* dir = cmd->add_option("--dir", opts->dir,
                              "rpg-style folder: stamped_groundtruth.txt, stamped_traj_estimate.txt, "
                              "optional eval_cfg.yaml and start_end_time.yaml")
                  ->check(CLI::ExistingDirectory);
  gt->excludes(dir);
  est->excludes(dir);
  gt->needs(est);
  est->needs(gt);
  cmd->add_option("--align", opts->align, "alignment (default sim3, or the folder's eval_cfg.yaml)")
      ->check(CLI::IsMember({"sim3", "se3", "posyaw", "none"}));
  auto* frames =
      cmd->add_option("--align-frames", opts->align_frames, "align over the first K matched poses; -1 = all")
          ->check(CLI::Validator(
              [](std::string& v) -> std::string {
                int k = 0;
                // Conversion errors are reported by CLI11 itself after validation.
                if (!CLI::detail::lexical_cast(v, k)) return "";
                return k == -1 || k > 0 ? "" : "must be -1 (all) or a positive count";
              },
              "-1|K>0"));
  cmd->add_option("--time-window", opts->time_window,
                  "start_end_time.yaml: keep pairs whose ground-truth stamp lies inside")
      ->check(CLI::ExistingFile);
  cmd->add_option("--json", opts->json, "write the result as JSON");
  cmd->add_option("--aligned", opts->aligned, "write the estimate in the ground truth's frame (TUM)");
  cmd->add_flag("--interpolate-gt", opts->interpolate_gt,
                "pair each pose with the ground truth interpolated at its time (not the toolbox's nearest "
                "stamp: fairer to poses at a higher rate than the ground truth)");
  cmd->add_flag("--rpe", opts->rpe,
                "also compute relative errors over 10..50 % of the ground-truth path length");
  cmd->callback([opts, frames] {
    opts->align_frames_given = frames->count() > 0;
    if (opts->dir.empty() && opts->gt.empty())
      throw CLI::ValidationError("eval", "give --gt and --est, or --dir");
    runEval(*opts);
  });
}

}  // namespace eds::app
