#include "report/html_report.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <stdexcept>

#include "core/version.hpp"
#include "io/output_file.hpp"
#include "report/assets.hpp"
#include "report/report_images.hpp"
#include "report/report_plots.hpp"
#include "report/svg_plot.hpp"
#include "system/reference_run.hpp"

namespace eds::report {

namespace {

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...) {
  char b[512];
  va_list args;
  va_start(args, f);
  std::vsnprintf(b, sizeof b, f, args);
  va_end(args);
  return b;
}

std::string row(const std::string& name, const std::string& value) {
  return "<tr><td>" + escapeXml(name) + "</td><td>" + escapeXml(value) + "</td></tr>";
}

double num(const nlohmann::json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : 0.0;
}

std::string summarySection(const RunData& run) {
  const nlohmann::json& s = run.summary;
  const nlohmann::json& c = s.value("counts", nlohmann::json::object());
  std::string t = "<h2>Summary</h2><table>";
  if (s.contains("inputs"))
    t += row("sequence", s["inputs"].value("sequence", "") + " (" + s["inputs"].value("format", "") + ")");
  t += row("mode", s.value("mode", "")) + row("sequence length", fmt("%.2f s", num(s, "sequence_s")));
  if (s.value("initialized", false)) {
    const nlohmann::json& in = s["initialization"];
    t +=
        row("initialized", fmt("%.2f s after the first frame, from %d frames, %d restarts",
                               num(in, "seconds_after_first_frame"), static_cast<int>(num(in, "frames_used")),
                               static_cast<int>(num(in, "restarts"))));
  } else {
    t += row("initialized", "never");
  }
  t += row("frames", fmt("%.0f in, %.0f tracked, %.0f not used (quality)", num(c, "frames"),
                         num(c, "tracked"), num(c, "frames_rejected")));
  if (num(c, "event_frames") > 0)
    t += row("event frames",
             fmt("%.0f of %.0f tracked", num(c, "event_frames_tracked"), num(c, "event_frames")));
  t += row("map", fmt("%.0f keyframes, %.0f points", num(c, "keyframes"), num(c, "map_points")));
  t += row("speed", fmt("%.2f s wall, real-time factor %.2f, peak memory %.0f MB", num(s, "wall_s"),
                        num(s, "real_time_factor"), num(s, "peak_rss_mb")));
  if (s.value("interrupted", false)) t += row("interrupted", fmt("at %.2f s", num(s, "interrupted_at_s")));
  for (const nlohmann::json& l : s.value("losses", nlohmann::json::array()))
    t += row("track lost", fmt("at %.2f s, ", num(l, "t_lost")) + escapeXml(l.value("cause", "")) + "; " +
                               (l.value("t_recovered", nlohmann::json()).is_number()
                                    ? fmt("recovered at %.2f s: ", num(l, "t_recovered")) +
                                          escapeXml(l.value("recovery", ""))
                                    : std::string("not recovered")));
  t += "</table><table><tr><th>stage (ms per item)</th><th>median</th><th>p95</th><th>max</th></tr>";
  const nlohmann::json timings = s.value("timings_ms", nlohmann::json::object());
  for (const auto& [key, st] : timings.items())
    if (st.is_object())
      t += "<tr><td>" + escapeXml(key) + "</td><td>" + fmt("%.2f", num(st, "median")) + "</td><td>" +
           fmt("%.2f", num(st, "p95")) + "</td><td>" + fmt("%.2f", num(st, "max")) + "</td></tr>";
  t += "</table>";
  const nlohmann::json fails = s.value("failures", nlohmann::json::array());
  t += "<details" + std::string(fails.empty() ? "" : " open") + "><summary>" + std::to_string(fails.size()) +
       " failures</summary><table><tr><th>t (s)</th><th>what</th></tr>";
  for (std::size_t i = 0; i < std::min<std::size_t>(fails.size(), 200); ++i)
    t += "<tr><td>" + fmt("%.3f", num(fails[i], "t")) + "</td><td>" +
         escapeXml(fails[i].value("reason", "")) + "</td></tr>";
  return t + "</table></details>";
}

// One row per evaluated trajectory: ATE, rotation, coverage; then RPE by sub-trajectory length.
std::string accuracyTables(const std::vector<std::pair<std::string, const TrajectoryEval*>>& evals) {
  std::string t =
      "<table><tr><th>trajectory</th><th>poses</th><th>matched</th><th>ATE RMSE (cm)</th><th>ATE median "
      "(cm)</th><th>rotation RMSE (deg)</th><th>rotation RMSE, orientations aligned "
      "(deg)</th><th>coverage</th>"
      "<th>sim3 scale</th></tr>";
  for (const auto& [name, e] : evals)
    t += "<tr><td>" + escapeXml(name) + "</td><td>" + std::to_string(e->est.size()) + "</td><td>" +
         std::to_string(e->ate.pairs.size()) + "</td><td>" + fmt("%.3f", 100 * e->ate.trans.rmse) +
         "</td><td>" + fmt("%.3f", 100 * e->ate.trans.median) + "</td><td>" + fmt("%.3f", e->ate.rot.rmse) +
         (eval::rotationFreeAboutPath(e->ate) ? " (straight path: free)" : "") + "</td><td>" +
         fmt("%.3f", e->ate.rot_oriented.rmse) + "</td><td>" + fmt("%.1f %%", 100 * e->ate.coverage) +
         "</td><td>" + fmt("%.4f", e->ate.transform.s) + "</td></tr>";
  t += "</table><table><tr><th>relative error</th><th>length (m)</th><th>pairs</th><th>translation RMSE "
       "(%)</th><th>rotation RMSE (deg)</th></tr>";
  for (const auto& [name, e] : evals)
    for (const eval::RpeResult& r : e->rpe)
      if (r.trans.num_samples > 0)
        t += "<tr><td>" + escapeXml(name) + "</td><td>" + fmt("%.2f", r.distance) + "</td><td>" +
             std::to_string(r.trans.num_samples) + "</td><td>" + fmt("%.2f", r.trans_perc.rmse) +
             "</td><td>" + fmt("%.3f", r.rot.rmse) + "</td></tr>";
  return t + "</table>";
}

// An inlined image shown `width` pixels wide.
std::string figure(const std::string& uri, int width, const std::string& caption) {
  return "<figure><img alt='" + escapeXml(caption) + "' width='" + std::to_string(width) + "' src='" + uri +
         "'><figcaption>" + escapeXml(caption) + "</figcaption></figure>";
}

// Up to `n` indices spread evenly over [0, size).
std::vector<std::size_t> spread(std::size_t size, std::size_t n) {
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < std::min(size, n); ++k)
    out.push_back(k * (size - 1) / std::max<std::size_t>(1, n - 1));
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::string keyframeSection(const RunData& run, TimeNs t0) {
  if (!run.is_run || !std::filesystem::exists(run.dir / "keyframes" / "index.txt")) return "";
  const Trajectory index = readReferenceIndex(run.dir);
  const CameraModel pinhole = readReferenceCamera(run.dir);
  std::string s =
      "<h2>Keyframes</h2><p class='sub'>The keyframe's image with its points coloured by inverse "
      "depth (near: red, far: blue), and the points alone: the keyframe's depth.</p>";
  for (std::size_t i : spread(index.size(), 4)) {
    const Keyframe kf = readReferenceKeyframe(run.dir, pinhole, index, i);
    const std::string when =
        fmt("keyframe %zu at %.2f s, %zu points", i, toSeconds(kf.t - t0), kf.points.size());
    const cv::Mat points = keyframePointsImage(kf), depth = keyframeDepthImage(kf);
    s += "<div class='row'>" + figure(jpegDataUri(points), points.cols, when) +
         figure(jpegDataUri(depth), depth.cols, "its depth") + "</div>";
  }
  return s;
}

std::string eventFrameSection(const RunData& run, TimeNs t0) {
  if (run.snapshots.empty()) return "";
  std::string s =
      "<h2>Event frames and the model</h2><p class='sub'>An event frame &Delta;L (sum of polarities, "
      "red positive, blue negative) next to the event generation model's prediction "
      "&Delta;L&#770; = &minus;&nabla;L&middot;v&Delta;t at the tracked pose, drawn at the keyframe's "
      "points (the first event frame tracked against keyframes spread over the run).</p>";
  for (std::size_t i : spread(run.snapshots.size(), 4)) {
    const EventFrameSnapshot& e = run.snapshots[i];
    const int width = e.delta.cols * displayScale(e.delta.cols);
    s += "<div class='row'>" +
         figure(pngDataUri(signedImage(e.delta)), width, fmt("event frame at %.3f s", toSeconds(e.t - t0))) +
         figure(pngDataUri(signedImage(e.predicted)), width,
                fmt("prediction (correlation %.2f)", e.correlation)) +
         "</div>";
  }
  return s;
}

std::string view3dSection(const std::string& data_json) {
  return "<h2>Map and camera path in 3D</h2><p class='sub'>Drag to orbit, wheel to zoom, double-click to "
         "reset. "
         "Grey: map points; blue squares: keyframes.</p><canvas id='view3d' width='900' "
         "height='560'></canvas>"
         "<script type='application/json' id='view3d-data'>" +
         data_json + "</script><script>" + kView3dJs + "</script>";
}

}  // namespace

namespace {

// The ground truth over the estimate's time span (with half a second either side).
Trajectory clipTo(const Trajectory& gt, const Trajectory& est) {
  if (est.empty()) return gt;
  Trajectory out;
  for (const StampedPose& p : gt)
    if (p.t >= est.front().t - 500'000'000 && p.t <= est.back().t + 500'000'000) out.push_back(p);
  return out;
}

const Trajectory& primary(const RunData& run) { return run.events.empty() ? run.frames : run.events; }

std::string gtNote(const ReportInputs& in, bool matched) {
  if (!in.gt)
    return "<p class='sub'>No ground truth (the run folder has no groundtruth.txt; give --gt FILE): "
           "trajectories as estimated, in the first camera's frame and the map's arbitrary scale.</p>";
  if (!matched)
    return "<p class='warn'>No pose is within 20 ms of a ground-truth pose: nothing to evaluate.</p>";
  return "<p class='sub'>Against " + escapeXml(in.gt_source) +
         ": sim3 alignment over the whole trajectory, errors as rpg_trajectory_evaluation computes them (as "
         "<code>eds eval</code>).</p>";
}

std::string singleReport(const ReportInputs& in) {
  const RunData& run = in.runs.front();
  std::string page = htmlPageStart("eds report: " + run.name);
  if (run.is_run) page += summarySection(run);
  const std::vector<TrajectoryEval> evals = in.gt ? evaluateRun(run, *in.gt) : std::vector<TrajectoryEval>{};
  eval::Sim3 align;
  Vec3 up(0, -1, 0);  // the first camera's frame: y points down
  std::vector<PathToDraw> paths;
  page += "<h2>Accuracy</h2>" + gtNote(in, !evals.empty());
  if (!evals.empty()) {
    align = evals.front().ate.transform, up = Vec3(0, 0, 1);
    std::vector<std::pair<std::string, const TrajectoryEval*>> rows;
    for (const TrajectoryEval& e : evals) rows.emplace_back(e.label, &e);
    page += accuracyTables(rows);
    paths.push_back({"ground truth", kGtColour, clipTo(*in.gt, primary(run)), true});
  }
  // Each trajectory through its own evaluation's alignment (one per map segment), when it has one.
  const auto aligned = [&](const Trajectory& traj, const std::string& label) {
    for (const TrajectoryEval& e : evals)
      if (e.label == label) return eval::alignedEstimate(traj, e.ate);
    return eval::applySim3(traj, align);
  };
  if (!run.events.empty())
    paths.push_back({"event-rate poses", kEventsColour, aligned(run.events, "event-rate poses")});
  const std::string frames_label = run.is_run ? "frame poses" : "poses";
  if (!run.frames.empty()) paths.push_back({frames_label, kFramesColour, aligned(run.frames, frames_label)});
  TimeNs t0 = primary(run).empty() ? 0 : primary(run).front().t;
  if (!run.frames.empty()) t0 = std::min(t0, run.frames.front().t);
  page += "<h2>Trajectory</h2><div class='row'>" + trajectoryPlots(paths) + "</div>";
  if (!evals.empty()) {
    std::vector<ErrorsToDraw> errs;
    for (const TrajectoryEval& e : evals)
      errs.push_back({e.label, e.label == "event-rate poses" ? kEventsColour : kFramesColour, &e});
    page += "<h2>Error over time</h2><div class='row'>" + errorPlots(errs, *in.gt, t0) + "</div>";
  }
  if (const std::string timing = timingPlot(run); !timing.empty())
    page += "<h2>Timings</h2><div class='row'>" + timing + "</div>";
  page += keyframeSection(run, t0) + eventFrameSection(run, t0);
  page += view3dSection(view3dData(run, align, paths, up));
  return page + "</body></html>\n";
}

std::string compareReport(const ReportInputs& in) {
  std::string names;
  for (const RunData& r : in.runs) names += (names.empty() ? "" : ", ") + r.name;
  std::string page = htmlPageStart("eds report: " + names);
  std::vector<std::vector<TrajectoryEval>> evals;
  for (const RunData& r : in.runs)
    evals.push_back(in.gt ? evaluateRun(r, *in.gt) : std::vector<TrajectoryEval>{});
  const bool any = std::any_of(evals.begin(), evals.end(), [](const auto& e) { return !e.empty(); });
  page += "<h2>Runs</h2>" + gtNote(in, any) +
          "<table><tr><th>run</th><th>trajectory</th><th>poses</th><th>ATE RMSE (cm)</th><th>rotation RMSE, "
          "orientations aligned (deg)</th><th>coverage</th><th>real-time factor</th><th>failures</th></tr>";
  std::vector<PathToDraw> paths;
  std::vector<ErrorsToDraw> errs;
  if (any) paths.push_back({"ground truth", kGtColour, clipTo(*in.gt, primary(in.runs.front())), true});
  for (std::size_t i = 0; i < in.runs.size(); ++i) {
    const RunData& r = in.runs[i];
    const TrajectoryEval* e = evals[i].empty() ? nullptr : &evals[i].front();
    page += "<tr><td>" + escapeXml(r.name) + "</td><td>" + (e ? e->label : std::string("-")) + "</td><td>" +
            std::to_string(primary(r).size()) + "</td><td>" +
            (e ? fmt("%.3f", 100 * e->ate.trans.rmse) : "-") + "</td><td>" +
            (e ? fmt("%.3f", e->ate.rot_oriented.rmse) : "-") + "</td><td>" +
            (e ? fmt("%.1f %%", 100 * e->ate.coverage) : "-") + "</td><td>" +
            (r.is_run ? fmt("%.2f", num(r.summary, "real_time_factor")) : "-") + "</td><td>" +
            (r.is_run ? std::to_string(r.summary.value("failures", nlohmann::json::array()).size()) : "-") +
            "</td></tr>";
    paths.push_back({r.name, runColour(i), e ? eval::applySim3(primary(r), e->ate.transform) : primary(r)});
    if (e) errs.push_back({r.name, runColour(i), e});
  }
  page += "</table><h2>Trajectories</h2><div class='row'>" + trajectoryPlots(paths) + "</div>";
  const TimeNs t0 = primary(in.runs.front()).empty() ? 0 : primary(in.runs.front()).front().t;
  if (!errs.empty())
    page += "<h2>Error over time</h2><div class='row'>" + errorPlots(errs, *in.gt, t0) + "</div>";
  const eval::Sim3 align = evals.front().empty() ? eval::Sim3{} : evals.front().front().ate.transform;
  page += view3dSection(view3dData(in.runs.front(), align, paths, any ? Vec3(0, 0, 1) : Vec3(0, -1, 0)));
  return page + "</body></html>\n";
}

}  // namespace

std::string htmlPageStart(const std::string& title) {
  return "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><meta name='viewport' "
         "content='width=device-width, initial-scale=1'><title>" +
         escapeXml(title) + "</title><style>" + kReportCss + "</style></head><body><h1>" + escapeXml(title) +
         "</h1><p class='sub'>written by eds " + escapeXml(versionString()) + "</p>";
}

std::string buildReport(const ReportInputs& in) {
  if (in.runs.empty()) throw std::invalid_argument("buildReport: no run");
  return in.runs.size() == 1 ? singleReport(in) : compareReport(in);
}

void writeReport(const std::vector<std::filesystem::path>& runs, const std::filesystem::path& gt_file,
                 const std::filesystem::path& out) {
  ReportInputs in;
  for (const auto& r : runs) in.runs.push_back(loadRun(r));
  if (in.runs.empty()) throw std::invalid_argument("writeReport: no run");
  in.gt = findGroundTruth(in.runs.front(), gt_file);
  in.gt_source = gt_file.empty() ? (in.runs.front().dir / "groundtruth.txt").string() : gt_file.string();
  writeTextFile(out, buildReport(in));
}

}  // namespace eds::report
