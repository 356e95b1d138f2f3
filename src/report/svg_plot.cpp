#include "report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace eds::report {

namespace {

constexpr double kLeft = 62, kRight = 12, kTop = 28, kBottom = 44;  // margins around the plot area
constexpr std::size_t kMaxPoints = 3000;                            // per series: thinned beyond
// Inside each plot, so that one saved on its own (docs/images) looks as it does in a report.
constexpr const char* kStyle =
    "<style>text{font:11px system-ui,sans-serif;fill:#333}.plot-title{font-size:13px;font-weight:600}"
    ".grid{stroke:#e6e6e6}</style>";

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", v);
  return b;
}

std::string tickLabel(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", std::abs(v) < 1e-12 ? 0.0 : v);
  return b;
}

// Data range [lo, hi] to pixels [p0, p1] (p1 < p0 for the y axis).
struct Axis {
  double lo = 0, hi = 1, p0 = 0, p1 = 1;
  bool log = false;
  double operator()(double v) const {
    const double a = log ? std::log10(lo) : lo, b = log ? std::log10(hi) : hi, x = log ? std::log10(v) : v;
    return p0 + (x - a) / (b - a) * (p1 - p0);
  }
};

void widen(double& lo, double& hi) {
  if (!(hi > lo)) {
    const double pad = std::abs(lo) > 0 ? 0.05 * std::abs(lo) : 1.0;
    lo -= pad, hi += pad;
  }
}

// A frame, grid lines, ticks and axis labels.
void drawAxes(std::ostringstream& s, const Axis& ax, const Axis& ay, const std::vector<double>& xt,
              const std::vector<double>& yt, const std::string& xl, const std::string& yl, int w, int h) {
  s << "<rect x='" << kLeft << "' y='" << kTop << "' width='" << w - kLeft - kRight << "' height='"
    << h - kTop - kBottom << "' fill='#fff' stroke='#999'/>";
  for (double v : xt)
    s << "<line class='grid' x1='" << num(ax(v)) << "' x2='" << num(ax(v)) << "' y1='" << kTop << "' y2='"
      << h - kBottom << "'/><text x='" << num(ax(v)) << "' y='" << h - kBottom + 14
      << "' text-anchor='middle'>" << tickLabel(v) << "</text>";
  for (double v : yt)
    s << "<line class='grid' y1='" << num(ay(v)) << "' y2='" << num(ay(v)) << "' x1='" << kLeft << "' x2='"
      << w - kRight << "'/><text x='" << kLeft - 4 << "' y='" << num(ay(v) + 4) << "' text-anchor='end'>"
      << tickLabel(v) << "</text>";
  s << "<text x='" << (kLeft + w - kRight) / 2 << "' y='" << h - 8 << "' text-anchor='middle'>"
    << escapeXml(xl) << "</text><text transform='translate(14," << (kTop + h - kBottom) / 2
    << ") rotate(-90)' text-anchor='middle'>" << escapeXml(yl) << "</text>";
}

std::string open(int w, int h, const std::string& title) {
  std::ostringstream s;
  s << "<svg xmlns='http://www.w3.org/2000/svg' class='plot' width='" << w << "' height='" << h
    << "' viewBox='0 0 " << w << " " << h << "'><title>" << escapeXml(title) << "</title>" << kStyle
    << "<rect width='100%' height='100%' fill='#fafafa'/><text x='" << w / 2
    << "' y='17' text-anchor='middle' class='plot-title'>" << escapeXml(title) << "</text>";
  return s.str();
}

void drawSeries(std::ostringstream& s, const Series& se, const Axis& ax, const Axis& ay) {
  const std::size_t n = std::min(se.x.size(), se.y.size());
  const std::size_t step = std::max<std::size_t>(1, (n + kMaxPoints - 1) / kMaxPoints);
  std::string path;
  bool pen_down = false;
  for (std::size_t i = 0; i < n; i += step) {
    if (!std::isfinite(se.x[i]) || !std::isfinite(se.y[i])) {
      pen_down = false;
      continue;
    }
    const std::string px = num(ax(se.x[i])), py = num(ay(se.y[i]));
    if (se.dots)
      s << "<circle cx='" << px << "' cy='" << py << "' r='2' fill='" << se.color << "'/>";
    else
      path += (pen_down ? " L" : " M") + px + " " + py;
    pen_down = true;
  }
  if (!se.dots && !path.empty())
    s << "<path class='series' data-label='" << escapeXml(se.label) << "' d='" << path
      << "' fill='none' stroke='" << se.color << "' stroke-width='1.4'"
      << (se.dashed ? " stroke-dasharray='5 3'" : "") << "/>";
}

void drawLegend(std::ostringstream& s, const std::vector<Series>& series, int w) {
  double y = kTop + 12;
  for (const Series& se : series) {
    if (se.label.empty()) continue;
    s << "<line x1='" << w - kRight - 130 << "' x2='" << w - kRight - 112 << "' y1='" << y - 4 << "' y2='"
      << y - 4 << "' stroke='" << se.color << "' stroke-width='" << (se.dots ? 4 : 2) << "'"
      << (se.dashed ? " stroke-dasharray='5 3'" : "") << "/><text x='" << w - kRight - 108 << "' y='" << y
      << "'>" << escapeXml(se.label) << "</text>";
    y += 14;
  }
}

}  // namespace

std::string escapeXml(const std::string& in) {
  std::string out;
  out.reserve(in.size());
  for (char c : in) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::vector<double> niceTicks(double lo, double hi, int target) {
  widen(lo, hi);
  const double raw = (hi - lo) / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  const double step = (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
  std::vector<double> t;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step) t.push_back(v);
  return t;
}

std::string renderSvg(const LinePlot& p) {
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const Series& se : p.series)
    for (std::size_t i = 0; i < std::min(se.x.size(), se.y.size()); ++i)
      if (std::isfinite(se.x[i]) && std::isfinite(se.y[i]))
        x0 = std::min(x0, se.x[i]), x1 = std::max(x1, se.x[i]), y0 = std::min(y0, se.y[i]),
        y1 = std::max(y1, se.y[i]);
  if (!std::isfinite(x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  widen(x0, x1), widen(y0, y1);
  const double pw = p.width - kLeft - kRight, ph = p.height - kTop - kBottom;
  if (p.equal_axes) {  // grow the shorter range about its centre
    const double per_px = std::max((x1 - x0) / pw, (y1 - y0) / ph);
    const double cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
    x0 = cx - per_px * pw / 2, x1 = cx + per_px * pw / 2, y0 = cy - per_px * ph / 2,
    y1 = cy + per_px * ph / 2;
  } else {
    const double m = 0.04 * (y1 - y0);
    y0 -= m, y1 += m;
  }
  const Axis ax{x0, x1, kLeft, kLeft + pw}, ay{y0, y1, kTop + ph, kTop};
  std::ostringstream s;
  s << open(p.width, p.height, p.title);
  std::vector<double> xt = niceTicks(x0, x1), yt = niceTicks(y0, y1);
  std::erase_if(xt, [&](double v) { return v < x0 || v > x1; });
  std::erase_if(yt, [&](double v) { return v < y0 || v > y1; });
  drawAxes(s, ax, ay, xt, yt, p.x_label, p.y_label, p.width, p.height);
  for (const Series& se : p.series) drawSeries(s, se, ax, ay);
  drawLegend(s, p.series, p.width);
  s << "</svg>";
  return s.str();
}

BoxStats boxStats(std::vector<double> v) {
  BoxStats b;
  std::erase_if(v, [](double x) { return !std::isfinite(x); });
  if (v.empty()) return b;
  std::sort(v.begin(), v.end());
  const auto q = [&](double f) {
    const double pos = f * static_cast<double>(v.size() - 1);
    const std::size_t i = static_cast<std::size_t>(pos);
    const double frac = pos - static_cast<double>(i);
    return i + 1 < v.size() ? v[i] + frac * (v[i + 1] - v[i]) : v[i];
  };
  b.q1 = q(0.25), b.median = q(0.5), b.q3 = q(0.75);
  const double lo = b.q1 - 1.5 * (b.q3 - b.q1), hi = b.q3 + 1.5 * (b.q3 - b.q1);
  b.whisker_lo = b.q1, b.whisker_hi = b.q3;
  for (double x : v) {
    if (x < lo || x > hi)
      b.outliers.push_back(x);
    else
      b.whisker_lo = std::min(b.whisker_lo, x), b.whisker_hi = std::max(b.whisker_hi, x);
  }
  return b;
}

std::string renderSvg(const BoxPlot& p) {
  std::vector<BoxGroup> groups = p.groups;
  double y0 = std::numeric_limits<double>::infinity(), y1 = -y0;
  for (BoxGroup& g : groups) {
    if (p.log_y) std::erase_if(g.values, [](double x) { return !(x > 0); });
    for (double x : g.values)
      if (std::isfinite(x)) y0 = std::min(y0, x), y1 = std::max(y1, x);
  }
  if (!std::isfinite(y0)) y0 = p.log_y ? 0.1 : 0, y1 = 1;
  std::vector<double> yt;
  if (p.log_y) {
    y0 = std::pow(10.0, std::floor(std::log10(y0))), y1 = std::pow(10.0, std::ceil(std::log10(y1)));
    if (!(y1 > y0)) y1 = 10 * y0;
    for (double v = y0; v <= y1 * 1.0001; v *= 10) yt.push_back(v);
  } else {
    widen(y0, y1);
    yt = niceTicks(y0, y1);
    y0 = std::min(y0, yt.front()), y1 = std::max(y1, yt.back());
  }
  const double pw = p.width - kLeft - kRight, ph = p.height - kTop - kBottom;
  const Axis ay{y0, y1, kTop + ph, kTop, p.log_y};
  std::ostringstream s;
  s << open(p.width, p.height, p.title);
  drawAxes(s, Axis{0, 1, kLeft, kLeft + pw}, ay, {}, yt, "", p.y_label, p.width, p.height);
  const double slot = pw / std::max<std::size_t>(1, groups.size()), half = std::min(18.0, slot * 0.3);
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const double cx = kLeft + slot * (static_cast<double>(i) + 0.5);
    s << "<text x='" << num(cx) << "' y='" << p.height - kBottom + 14 << "' text-anchor='middle'>"
      << escapeXml(groups[i].label) << "</text>";
    if (groups[i].values.empty()) continue;
    const BoxStats b = boxStats(groups[i].values);
    s << "<g class='box' data-label='" << escapeXml(groups[i].label) << "' data-median='" << b.median << "'>"
      << "<line x1='" << num(cx) << "' x2='" << num(cx) << "' y1='" << num(ay(b.whisker_lo)) << "' y2='"
      << num(ay(b.whisker_hi)) << "' stroke='#333'/><rect x='" << num(cx - half) << "' y='" << num(ay(b.q3))
      << "' width='" << num(2 * half) << "' height='" << num(std::max(1.0, ay(b.q1) - ay(b.q3)))
      << "' fill='#9ecae1' stroke='#333'/><line x1='" << num(cx - half) << "' x2='" << num(cx + half)
      << "' y1='" << num(ay(b.median)) << "' y2='" << num(ay(b.median))
      << "' stroke='#d62728' stroke-width='2'/>";
    for (double o : b.outliers)
      s << "<circle cx='" << num(cx) << "' cy='" << num(ay(o)) << "' r='1.8' fill='none' stroke='#555'/>";
    s << "</g>";
  }
  s << "</svg>";
  return s.str();
}

}  // namespace eds::report
