// `eds report RUN_DIR [--gt FILE] [--out FILE]` and `eds report --compare RUN_A RUN_B ... [TUM files]`:
// one self-contained HTML page of a run, or of several runs overlaid.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "report/html_report.hpp"

namespace eds::app {

namespace {

struct ReportArgs {
  std::vector<std::string> runs;
  std::string gt, out;
  bool compare = false;
};

void runReport(const ReportArgs& a) {
  if (a.runs.size() > 1 && !a.compare)
    throw CLI::ValidationError("report", "several runs: pass --compare to overlay them");
  std::vector<std::filesystem::path> runs(a.runs.begin(), a.runs.end());
  std::filesystem::path out = a.out;
  if (out.empty())
    out = std::filesystem::is_directory(runs.front()) && !a.compare ? runs.front() / "report.html"
                                                                    : std::filesystem::path("report.html");
  report::writeReport(runs, a.gt, out);
  std::printf("wrote %s\n", out.string().c_str());
}

}  // namespace

void addReportCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "report", "Self-contained HTML report of a run (plots, images, 3D map), or of several runs compared");
  auto a = std::make_shared<ReportArgs>();
  cmd->add_option("runs", a->runs,
                  "Output folder of `eds run`; with --compare several, or TUM trajectory files")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("--gt", a->gt, "Ground truth (TUM); default: the run's groundtruth.txt if it has one")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", a->out, "HTML file to write (default: RUN_DIR/report.html, or report.html)");
  cmd->add_flag("--compare", a->compare, "Overlay several runs (and other systems' TUM files) in one report");
  cmd->callback([a] { runReport(*a); });
}

}  // namespace eds::app
