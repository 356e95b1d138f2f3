// `eds study depth-noise|contrast-noise --out DIR`: the paper's sensitivity studies on simulated
// building-like scenes; DIR/study.json and DIR/report.html (box plots and medians).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "io/output_file.hpp"
#include "report/study_report.hpp"
#include "study/sensitivity.hpp"

namespace eds::app {

namespace {

struct StudyArgs {
  std::string which, out = "study_out";
  study::StudyConfig cfg;
};

void runStudy(StudyArgs& a) {
  a.cfg.kind = a.which == "depth-noise" ? study::Kind::kDepthNoise : study::Kind::kContrastNoise;
  const std::filesystem::path out(a.out);
  requireWritableDir(out);
  a.cfg.work_dir = out / "sequences";
  std::printf("%-8s %6s %10s %12s %9s %10s\n", "level", "seed", "ATE (cm)", "rot (deg)", "coverage",
              "tracked");
  const study::StudyResult r = study::runStudy(a.cfg, [&](const study::StudyRun& run) {
    std::printf("%-8s %6llu %10.3f %12.3f %8.1f%% %6zu/%zu\n",
                study::levelName(a.cfg.kind, run.level).c_str(), static_cast<unsigned long long>(run.seed),
                run.ate_cm, run.rot_rmse_deg, 100 * run.coverage, run.tracked, run.event_frames);
    std::fflush(stdout);
  });
  std::filesystem::remove_all(a.cfg.work_dir);
  writeTextFile(out / "study.json", study::toJson(r).dump(1) + "\n");
  writeTextFile(out / "report.html", report::buildStudyReport(r));
  std::printf("%.0f s; wrote %s/study.json and %s/report.html\n", r.wall_s, a.out.c_str(), a.out.c_str());
}

}  // namespace

void addStudyCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "study",
      "The paper's sensitivity studies (tracking-only on simulated building-like scenes): box plots");
  auto a = std::make_shared<StudyArgs>();
  cmd->add_option("which", a->which, "depth-noise or contrast-noise")
      ->required()
      ->check(CLI::IsMember({"depth-noise", "contrast-noise"}));
  cmd->add_option("--out", a->out, "Output folder")->capture_default_str();
  cmd->add_option("--levels", a->cfg.levels,
                  "Levels to run (depth: fractions of the median depth, default 0.01 0.05 0.1 0.2 0.3 0.5; "
                  "contrast: sigma_C, default 0.05 to 0.3 by 0.05)");
  cmd->add_option("--seeds", a->cfg.seeds, "Scene and noise seeds, one sequence each")->capture_default_str();
  cmd->add_option("--duration", a->cfg.duration_s, "Seconds of each simulated sequence")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 60.0));
  cmd->callback([a] { runStudy(*a); });
}

}  // namespace eds::app
