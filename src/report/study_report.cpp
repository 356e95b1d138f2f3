#include "report/study_report.hpp"

#include <algorithm>
#include <cstdio>

#include "report/html_report.hpp"
#include "report/svg_plot.hpp"

namespace eds::report {

namespace {

std::string cell(double v, const char* f) {
  char b[48];
  std::snprintf(b, sizeof b, f, v);
  return "<td>" + std::string(b) + "</td>";
}

std::vector<double> levelsOf(const study::StudyResult& r) {
  std::vector<double> levels;
  for (const study::StudyRun& run : r.runs)
    if (std::find(levels.begin(), levels.end(), run.level) == levels.end()) levels.push_back(run.level);
  return levels;
}

// Per level: median of the pooled per-pose errors, median of the runs' RMSEs, coverage, failures.
std::string mediansTable(const study::StudyResult& r) {
  std::string t =
      "<table><tr><th>level</th><th>runs</th><th>median translation error (cm)</th><th>median rotation error "
      "(deg)</th><th>median ATE RMSE (cm)</th><th>median rotation RMSE (deg)</th><th>mean "
      "coverage</th><th>event "
      "frames tracked</th></tr>";
  for (double level : levelsOf(r)) {
    std::vector<double> trans, rot, ate, rrmse;
    double coverage = 0;
    std::size_t n = 0, frames = 0, tracked = 0;
    for (const study::StudyRun& run : r.runs) {
      if (run.level != level) continue;
      trans.insert(trans.end(), run.trans_cm.begin(), run.trans_cm.end());
      rot.insert(rot.end(), run.rot_deg.begin(), run.rot_deg.end());
      ate.push_back(run.ate_cm), rrmse.push_back(run.rot_rmse_deg);
      coverage += run.coverage, frames += run.event_frames, tracked += run.tracked, ++n;
    }
    t += "<tr><td>" + escapeXml(study::levelName(r.kind, level)) + "</td><td>" + std::to_string(n) + "</td>" +
         cell(boxStats(trans).median, "%.3f") + cell(boxStats(rot).median, "%.3f") +
         cell(boxStats(ate).median, "%.3f") + cell(boxStats(rrmse).median, "%.3f") +
         cell(100 * coverage / std::max<std::size_t>(1, n), "%.1f %%") + "<td>" + std::to_string(tracked) +
         " / " + std::to_string(frames) + "</td></tr>";
  }
  return t + "</table>";
}

std::string boxPlots(const study::StudyResult& r) {
  BoxPlot trans, rot;
  trans.title = "translation error per pose", trans.y_label = "cm";
  rot.title = "rotation error per pose", rot.y_label = "deg";
  trans.log_y = rot.log_y = true;
  trans.width = rot.width = 540;
  for (double level : levelsOf(r)) {
    BoxGroup gt{study::levelName(r.kind, level), {}}, gr{study::levelName(r.kind, level), {}};
    for (const study::StudyRun& run : r.runs)
      if (run.level == level) {
        gt.values.insert(gt.values.end(), run.trans_cm.begin(), run.trans_cm.end());
        gr.values.insert(gr.values.end(), run.rot_deg.begin(), run.rot_deg.end());
      }
    trans.groups.push_back(std::move(gt)), rot.groups.push_back(std::move(gr));
  }
  return "<div class='row'>" + renderSvg(trans) + renderSvg(rot) + "</div>";
}

}  // namespace

std::string buildStudyReport(const study::StudyResult& r) {
  std::size_t seeds = 0;
  for (const study::StudyRun& run : r.runs) seeds += run.level == r.runs.front().level;
  char what[400];
  std::snprintf(
      what, sizeof what,
      "Tracking-only (events against keyframes with the true depth, `eds track --depth-from-gt`) on "
      "simulated building-like scenes (preset building, median depth %.1f m), %zu seeds per level; "
      "errors of every pose against the ground truth without alignment. %.0f s in all.",
      r.median_scene_depth_m, seeds, r.wall_s);
  return htmlPageStart("eds study: " + r.title) + "<p class='sub'>" + escapeXml(what) +
         "</p><h2>Medians</h2>" + mediansTable(r) + "<h2>Errors by " + escapeXml(r.level_label) + "</h2>" +
         boxPlots(r) + "</body></html>\n";
}

}  // namespace eds::report
