#include "report/report_plots.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "report/svg_plot.hpp"

namespace eds::report {

namespace {

const char* const kAxisNames[] = {"x", "y", "z"};

std::string coord(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.5g", v);
  return b;
}

std::string flatArray(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + coord(v[i]);
  return s + "]";
}

}  // namespace

const char* runColour(std::size_t i) {
  static const char* const kColours[] = {"#d62728", "#1f77b4", "#2ca02c", "#ff7f0e",
                                         "#9467bd", "#8c564b", "#e377c2", "#17becf"};
  return kColours[i % std::size(kColours)];
}

std::string trajectoryPlots(const std::vector<PathToDraw>& paths) {
  if (paths.empty()) return "";
  // Axes ordered by the extent of the first path.
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const StampedPose& p : paths.front().poses)
    lo = lo.cwiseMin(p.T_w_c.translation()), hi = hi.cwiseMax(p.T_w_c.translation());
  std::array<int, 3> ax{0, 1, 2};
  std::sort(ax.begin(), ax.end(), [&](int a, int b) { return hi[a] - lo[a] > hi[b] - lo[b]; });
  std::string out;
  for (const auto& [a, b, title] :
       {std::tuple{ax[0], ax[1], "from above"}, std::tuple{ax[0], ax[2], "from the side"}}) {
    LinePlot plot;
    plot.title = std::string("trajectory ") + title;
    plot.x_label = std::string(kAxisNames[a]) + " (m)";
    plot.y_label = std::string(kAxisNames[b]) + " (m)";
    plot.equal_axes = true;
    plot.width = 540, plot.height = 400;
    for (const PathToDraw& p : paths) {
      Series s;
      s.label = p.label, s.color = p.color, s.dashed = p.dashed;
      for (const StampedPose& q : p.poses)
        s.x.push_back(q.T_w_c.translation()[a]), s.y.push_back(q.T_w_c.translation()[b]);
      plot.series.push_back(std::move(s));
    }
    out += renderSvg(plot);
  }
  return out;
}

std::string errorPlots(const std::vector<ErrorsToDraw>& errors, const Trajectory& gt, TimeNs t0) {
  LinePlot trans, rot;
  trans.title = "translation error (sim3-aligned)", rot.title = "rotation error";
  trans.x_label = rot.x_label = "time (s)";
  trans.y_label = "error (cm)", rot.y_label = "error (deg)";
  for (const ErrorsToDraw& e : errors) {
    Series st, sr;
    st.label = sr.label = e.label, st.color = sr.color = e.color;
    const eval::AteResult& ate = e.eval->ate;
    for (std::size_t i = 0; i < ate.pairs.size(); ++i) {
      const double t = toSeconds(gt[ate.pairs[i].gt].t - t0);
      st.x.push_back(t), st.y.push_back(100 * ate.trans_errors[i]);
      sr.x.push_back(t), sr.y.push_back(ate.rot_errors_deg[i]);
    }
    trans.series.push_back(std::move(st)), rot.series.push_back(std::move(sr));
  }
  return renderSvg(trans) + renderSvg(rot);
}

std::string timingPlot(const RunData& run) {
  if (!run.timings.is_object()) return "";
  BoxPlot plot;
  plot.title = "time per item (ms)", plot.y_label = "ms", plot.log_y = true, plot.width = 540;
  const std::pair<const char*, const char*> stages[] = {{"event_tracking", "event frame"},
                                                        {"frame_tracking", "frame"},
                                                        {"mapping", "mapping / kf"},
                                                        {"backend_per_keyframe", "back-end / kf"},
                                                        {"realtime_latency", "pose latency"}};
  for (const auto& [key, label] : stages) {
    if (!run.timings.contains(key) || run.timings[key].empty()) continue;
    plot.groups.push_back({label, run.timings[key].get<std::vector<double>>()});
  }
  return plot.groups.empty() ? "" : renderSvg(plot);
}

std::string view3dData(const RunData& run, const eval::Sim3& align, const std::vector<PathToDraw>& paths,
                       const Vec3& up, std::size_t max_points) {
  const std::size_t n = run.map.xyz.size(),
                    step = std::max<std::size_t>(1, (n + max_points - 1) / max_points);
  std::vector<double> pts, inten, kfs;
  for (std::size_t i = 0; i < n; i += step) {
    const Vec3 p = align.apply(run.map.xyz[i].cast<double>());
    if (!p.allFinite()) continue;
    pts.insert(pts.end(), {p.x(), p.y(), p.z()});
    inten.push_back(i < run.map.intensity.size() ? std::clamp<double>(run.map.intensity[i], 0, 1) : 0.5);
  }
  for (const StampedPose& k : run.keyframes) {
    const Vec3 p = align.apply(k.T_w_c.translation());
    kfs.insert(kfs.end(), {p.x(), p.y(), p.z()});
  }
  std::string s = "{\"up\":" + flatArray({up.x(), up.y(), up.z()}) + ",\"points\":" + flatArray(pts) +
                  ",\"intensity\":" + flatArray(inten) + ",\"keyframes\":" + flatArray(kfs) + ",\"paths\":[";
  for (std::size_t i = 0; i < paths.size(); ++i) {
    std::vector<double> xyz;
    for (const StampedPose& q : paths[i].poses)
      xyz.insert(xyz.end(),
                 {q.T_w_c.translation().x(), q.T_w_c.translation().y(), q.T_w_c.translation().z()});
    s += std::string(i ? "," : "") + "{\"color\":\"" + paths[i].color + "\",\"xyz\":" + flatArray(xyz) + "}";
  }
  return s + "]}";
}

}  // namespace eds::report
