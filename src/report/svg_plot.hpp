#pragma once
// Plots as inline SVG for the HTML report: line/dot plots (trajectories, errors over time) and box
// plots (timings, study results). Plain SVG text, so that a report needs no plotting library at view
// time and a test can read the numbers back.
#include <string>
#include <vector>

namespace eds::report {

struct Series {
  std::string label, color;
  std::vector<double> x, y;  // same length; non-finite points break the line
  bool dots = false;         // markers instead of a line
  bool dashed = false;
};

struct LinePlot {
  std::string title, x_label, y_label;
  std::vector<Series> series;
  bool equal_axes = false;  // one unit is as long on both axes (trajectories seen from above)
  int width = 460, height = 320;
};

struct BoxGroup {
  std::string label;
  std::vector<double> values;
};

struct BoxPlot {
  std::string title, y_label;
  std::vector<BoxGroup> groups;
  bool log_y = false;  // values must then be positive (others are left out)
  int width = 460, height = 300;
};

// Quartiles and Tukey whiskers (1.5 IQR) as box plots draw them; quantiles interpolate linearly, as
// numpy's default.
struct BoxStats {
  double q1 = 0, median = 0, q3 = 0, whisker_lo = 0, whisker_hi = 0;
  std::vector<double> outliers;
};
BoxStats boxStats(std::vector<double> values);

// Round tick values covering [lo, hi], about `target` of them (steps of 1, 2 or 5 x 10^k).
std::vector<double> niceTicks(double lo, double hi, int target = 5);

std::string renderSvg(const LinePlot& plot);
std::string renderSvg(const BoxPlot& plot);

// Text for SVG and HTML (& < > " escaped).
std::string escapeXml(const std::string& s);

}  // namespace eds::report
