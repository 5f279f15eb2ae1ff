#include <cmath>

#include <gtest/gtest.h>

#include "core/svg_line_plot.h"

namespace chordfit {
namespace {

TEST(NiceTicks, UseOneTwoFiveSteps) {
  EXPECT_EQ(niceTicks(0.0, 10.0, 5), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  const auto ticks = niceTicks(0.95, 1.05, 5);
  ASSERT_GE(ticks.size(), 5u);
  EXPECT_NEAR(ticks[1] - ticks[0], 0.02, 1e-12);
  EXPECT_LE(ticks.front(), 0.95);
  EXPECT_GE(ticks.back(), 1.05 - 1e-12);
}

// Log-axis ticks are values of 1, 2, 5 x 10^k that cover the range (the convergence plot's
// cost axis): 158, 251, 398 were the ticks of equal exponent steps before.
TEST(LogTicks, UseOneTwoFiveValuesCoveringTheRangeAndThinLongRanges) {
  const std::vector<double> ticks = logTicks(2.0, std::log10(1201.0));
  ASSERT_EQ(ticks.size(), 5u);
  const double expected[] = {100, 200, 500, 1000, 2000};
  for (std::size_t i = 0; i < ticks.size(); ++i) EXPECT_NEAR(ticks[i], expected[i], 1e-9);
  // A cost of 1e308 (a failed closure) on the axis gave ~309 gridlines.
  const std::vector<double> decades = logTicks(0.0, 300.0);
  EXPECT_LE(decades.size(), 10u);
  EXPECT_LE(decades.front(), 1.0);
  EXPECT_GE(std::log10(decades.back()), 300.0 - 1e-9);
}

TEST(SvgLinePlots, WritesOnePathPerSeriesAndEscapesLabels) {
  PlotPanel panel{"cost <history>", "iteration", "cost", {}, true};
  panel.series.push_back({"ceres & co", {0, 1, 2}, {10, 1, 0.1}, true, true});
  panel.series.push_back({"bobyqa", {0, 1, 2}, {10, NAN, 0.5}, false, true});
  const std::string svg = svgLinePlots({panel, panel}, 2);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("cost &lt;history&gt;"), std::string::npos);
  EXPECT_NE(svg.find("ceres &amp; co"), std::string::npos);
  std::size_t paths = 0;
  for (std::size_t at = svg.find("<path"); at != std::string::npos;
       at = svg.find("<path", at + 1)) {
    ++paths;
  }
  EXPECT_EQ(paths, 4u);  // 2 series x 2 panels
  EXPECT_NE(svg.find("width='1120'"), std::string::npos);
}

// Markers of their own shape, colour and size (convergence.svg's stages), each drawn over
// every line and shown in the legend as drawn; a legend margin puts the legend right of the
// frame, off the data.
TEST(SvgLinePlots, DrawsMarkersOfEachShapeOverTheLinesAndTheLegendInItsMargin) {
  PlotPanel panel{"stages", "x", "y", {}, false, 150.0};
  panel.series.push_back({"line", {0, 1, 2}, {0, 1, 2}, false, true, false, "#123456"});
  const PlotMarker shapes[] = {PlotMarker::kCircle, PlotMarker::kSquare, PlotMarker::kDiamond,
                               PlotMarker::kTriangleUp, PlotMarker::kTriangleDown};
  for (const PlotMarker shape : shapes) {
    PlotSeries stage{"stage", {1}, {1}, true, false, false, "#abcdef", shape, 6.0};
    panel.series.push_back(stage);
  }
  const std::string svg = svgLinePlots({panel}, 1, 600, 300);
  auto count = [&](const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = svg.find(what); at != std::string::npos; at = svg.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("stroke='#123456'"), 2u) << "the line and its legend sample";
  // Each shape twice (the point and its legend entry), with a white rim at 6 px.
  EXPECT_EQ(count("fill='#abcdef' stroke='white'"), 10u);
  EXPECT_EQ(count("<circle"), 2u);
  EXPECT_EQ(count("<rect x="), 2u + 1u) << "the squares and the frame";
  EXPECT_EQ(count("<polygon"), 6u) << "diamonds and triangles";
  EXPECT_LT(svg.find("<path"), svg.find("<circle")) << "markers over the lines";
  // The frame ends 15 + 150 px from the right; the legend's text starts beyond it.
  const std::size_t label = svg.find(">line</text>");
  const std::size_t x = svg.rfind("x='", label) + 3;
  EXPECT_GT(std::stod(svg.substr(x, svg.find('\'', x) - x)), 600.0 - 165.0);
}

// A series drawn on top has its markers over those of the series after it, while its legend
// entry keeps its place: convergence.svg's segment pre-fit diamond was hidden under the run of
// COBYLA's small circles that starts at the same closure.
TEST(SvgLinePlots, DrawsTheMarkersOfASeriesOnTopLastAndKeepsTheLegendOrder) {
  PlotPanel panel{"stages", "x", "y", {}, false, 150.0};
  PlotSeries stage{"pre-fit", {2}, {1}, true, false, false, "#009E73", PlotMarker::kDiamond, 6.0};
  stage.on_top = true;
  panel.series.push_back(stage);
  panel.series.push_back({"iterations",
                          {2, 3, 4},
                          {1, 1, 1},
                          true,
                          false,
                          false,
                          "#0072B2",
                          PlotMarker::kCircle,
                          3.5});
  const std::string svg = svgLinePlots({panel}, 1, 600, 300);
  const std::size_t diamond = svg.find("<polygon");
  const std::size_t last_circle = svg.rfind("<circle");
  ASSERT_NE(diamond, std::string::npos);
  ASSERT_NE(last_circle, std::string::npos);
  EXPECT_GT(diamond, svg.find("<circle")) << "the diamond over the first circle";
  EXPECT_LT(svg.find(">pre-fit</text>"), svg.find(">iterations</text>")) << "legend order kept";
}

// A point at the data's extreme keeps its marker inside the frame, even when a tick falls just
// below it (costs of 507 on a log axis from 500 put half of each marker under the frame).
TEST(SvgLinePlots, KeepsMarkersAtTheDataExtremesInsideTheFrame) {
  PlotPanel panel{"cost", "forward runs", "cost", {}, true};
  PlotSeries points{"cost", {0, 10, 20, 30}, {5000, 900, 507, 507}, true, false};
  points.marker_radius = 4.0;
  panel.series.push_back(points);
  const std::string svg = svgLinePlots({panel}, 1, 600, 300);
  auto attribute = [&](std::size_t from, const std::string& name) {
    const std::size_t at = svg.find(" " + name + "='", from) + name.size() + 3;
    return std::stod(svg.substr(at, svg.find('\'', at) - at));
  };
  const std::size_t frame = svg.find("<rect x=");
  const double left = attribute(frame, "x"), top = attribute(frame, "y");
  const double right = left + attribute(frame, "width"), bottom = top + attribute(frame, "height");
  int markers = 0;
  for (std::size_t at = svg.find("<circle"); at != std::string::npos;
       at = svg.find("<circle", at + 1)) {
    const double cx = attribute(at, "cx"), cy = attribute(at, "cy"), r = attribute(at, "r");
    if (cx > right) continue;  // the legend's sample
    ++markers;
    EXPECT_GE(cx - r, left) << svg.substr(at, 80);
    EXPECT_LE(cx + r, right) << svg.substr(at, 80);
    EXPECT_GE(cy - r, top) << svg.substr(at, 80);
    EXPECT_LE(cy + r, bottom) << svg.substr(at, 80);
  }
  EXPECT_GE(markers, 4);  // and the legend's sample, when inside the frame
}

}  // namespace
}  // namespace chordfit
