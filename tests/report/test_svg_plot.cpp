// The report's SVG plots: tick choice, box-plot statistics (numpy's conventions), and that the
// drawing maps data to pixels as the axes say.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <regex>
#include <sstream>

#include "report/svg_plot.hpp"

namespace eds::report {
namespace {

TEST(SvgPlot, NiceTicksAreRoundStepsInsideTheRange) {
  const std::vector<double> t = niceTicks(0.03, 0.97);
  ASSERT_EQ(t.size(), 4u);
  for (std::size_t i = 0; i < t.size(); ++i) EXPECT_NEAR(t[i], 0.2 * (i + 1), 1e-12);
  const std::vector<double> big = niceTicks(-1234, 5678, 5);  // 6912 / 5 rounds to steps of 1000
  ASSERT_EQ(big.size(), 7u);
  EXPECT_DOUBLE_EQ(big.front(), -1000);
  EXPECT_DOUBLE_EQ(big.back(), 5000);
}

TEST(SvgPlot, BoxStatsFollowNumpyPercentilesAndTukeyWhiskers) {
  // numpy.percentile([1, 2, 3, 4, 100], [25, 50, 75]) = [2, 3, 4]; fences 2 - 3 and 4 + 3.
  const BoxStats b = boxStats({100, 3, 1, 4, 2});
  EXPECT_DOUBLE_EQ(b.q1, 2);
  EXPECT_DOUBLE_EQ(b.median, 3);
  EXPECT_DOUBLE_EQ(b.q3, 4);
  EXPECT_DOUBLE_EQ(b.whisker_lo, 1);
  EXPECT_DOUBLE_EQ(b.whisker_hi, 4);
  ASSERT_EQ(b.outliers.size(), 1u);
  EXPECT_DOUBLE_EQ(b.outliers[0], 100);
  // Interpolated: numpy.percentile([1, 2, 3, 4], 25) = 1.75.
  EXPECT_DOUBLE_EQ(boxStats({4, 3, 2, 1}).q1, 1.75);
}

// The pixel coordinates of the first drawn series.
std::vector<std::pair<double, double>> seriesPixels(const std::string& svg) {
  std::smatch m;
  std::vector<std::pair<double, double>> px;
  if (!std::regex_search(svg, m, std::regex("class='series'[^>]* d='([^']*)'"))) return px;
  std::istringstream in(m[1].str());
  std::string op;
  double x = 0, y = 0;
  while (in >> op >> y) {
    x = std::stod(op.substr(1));
    px.emplace_back(x, y);
  }
  return px;
}

TEST(SvgPlot, EqualAxesDrawASquareAsASquare) {
  LinePlot p;
  p.equal_axes = true, p.width = 500, p.height = 300;
  Series s;
  s.label = "square";
  s.x = {0, 2, 2, 0, 0}, s.y = {0, 0, 2, 2, 0};
  p.series.push_back(s);
  const auto px = seriesPixels(renderSvg(p));
  ASSERT_EQ(px.size(), 5u);
  const double w = px[1].first - px[0].first, h = px[1].second - px[2].second;  // y grows downwards
  EXPECT_GT(w, 50);
  EXPECT_NEAR(w, h, 0.2);
  // Without equal axes the square fills the plot's width and height separately.
  p.equal_axes = false;
  const auto free = seriesPixels(renderSvg(p));
  EXPECT_GT(free[1].first - free[0].first, 1.3 * (free[1].second - free[2].second));
}

TEST(SvgPlot, NonFiniteValuesBreakTheLineAndTextIsEscaped) {
  LinePlot p;
  p.title = "a < b & c";
  Series s;
  s.x = {0, 1, 2, 3, 4}, s.y = {0, 1, std::nan(""), 3, 4};
  p.series.push_back(s);
  const std::string svg = renderSvg(p);
  EXPECT_NE(svg.find("a &lt; b &amp; c"), std::string::npos);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(svg, m, std::regex(" d='([^']*)'")));
  const std::string d = m[1].str();
  EXPECT_EQ(std::count(d.begin(), d.end(), 'M'), 2);  // two pieces
  EXPECT_EQ(std::count(d.begin(), d.end(), 'L'), 2);
}

}  // namespace
}  // namespace eds::report
