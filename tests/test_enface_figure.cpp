// The atrial (surgeon's) view of a closed valve (core/enface_figure.h) on the open parametric
// valve: content, drawing order and the tissue outline; and `simulate` writing it.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/enface_figure.h"
#include "core/metrics.h"
#include "core/parametric_valve.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

using testing::occurrences;

ParametricValve coarseValve() {
  ValveParameters parameters;
  parameters.target_edge_mm = 3.0;
  return makeParametricValve(parameters);
}

TEST(EnfaceFigure, DrawsEveryTriangleOverTheOrificeWithTheTissueOutline) {
  const ParametricValve valve = coarseValve();
  const ValveCase& c = valve.valve_case;
  const std::string svg = enfaceFigureSvg(c, c.mesh.V, {"open <valve> & co", 0.5, 12.0});
  EXPECT_EQ(occurrences(svg, "<polygon points="), static_cast<std::size_t>(c.mesh.F.rows()))
      << "one polygon per triangle";
  EXPECT_EQ(occurrences(svg, "class=\"orifice\""), 1u);
  EXPECT_EQ(occurrences(svg, "class=\"annulus\""), 1u);
  EXPECT_NE(svg.find("stroke-width=\"12\""), std::string::npos)
      << "outline 2 x 0.5 mm at 12 px/mm: the triangle grown by the tissue radius";
  EXPECT_NE(svg.find("open &lt;valve&gt; &amp; co"), std::string::npos) << "title escaped";
  EXPECT_NE(svg.find(">anterior leaflet<"), std::string::npos);
  EXPECT_NE(svg.find(">open orifice<"), std::string::npos);
  // The orifice is drawn first (under the leaflets), the ring outline last.
  EXPECT_LT(svg.find("class=\"orifice\""), svg.find("<polygon points="));
  EXPECT_GT(svg.find("class=\"annulus\""), svg.rfind("<polygon points="));
}

// The fills of the leaflet polygons, in drawing order.
std::vector<std::string> polygonFills(const std::string& svg) {
  std::vector<std::string> fills;
  for (std::size_t at = svg.find("<polygon points="); at != std::string::npos;
       at = svg.find("<polygon points=", at + 1)) {
    const std::size_t fill = svg.find("fill=\"", at) + 6;
    fills.push_back(svg.substr(fill, svg.find('"', fill) - fill));
  }
  return fills;
}

TEST(EnfaceFigure, DrawsTheHighestTissueLastAsSeenFromTheAtrium) {
  const ParametricValve valve = coarseValve();
  const ValveCase& c = valve.valve_case;
  // Lift one free-edge vertex 100 mm toward the atrium: its triangles are then the only ones
  // above the annulus (lightest shade), and must be drawn last, over the rest.
  Eigen::MatrixXd V = c.mesh.V;
  const int lifted = valve.free_edge(0);
  V.row(lifted) += 100.0 * closedAnnulus(c).frame.plane.normal.transpose();
  int incident = 0;
  for (Eigen::Index f = 0; f < c.mesh.F.rows(); ++f)
    incident += (c.mesh.F.row(f).array() == lifted).any();
  ASSERT_GT(incident, 0);
  const std::vector<std::string> fills = polygonFills(enfaceFigureSvg(c, V, {"", 0.0, 12.0}));
  ASSERT_EQ(fills.size(), static_cast<std::size_t>(c.mesh.F.rows()));
  const std::string lightest = fills.back();
  for (int k = 1; k <= incident; ++k) EXPECT_EQ(fills[fills.size() - k], lightest) << k;
  for (std::size_t k = 0; k + incident < fills.size(); ++k) EXPECT_NE(fills[k], lightest) << k;
}

// The top of a figure's height scale: the number after "≥ ".
double scaleTop(const std::string& svg) {
  const std::string at_least = "\xE2\x89\xA5 ";
  const std::size_t at = svg.find(at_least);
  if (at == std::string::npos) return NAN;
  return std::stod(svg.substr(at + at_least.size()));
}

// The figure's size: its <svg> element's width and height attributes.
std::string figureSize(const std::string& svg) {
  const std::size_t from = svg.find("width=\""), to = svg.find("font-family");
  return svg.substr(from, to - from);
}

// compare's figures share one height scale (a shade is one height in every file; truth,
// heuristic and manual topped out at 4, 8 and 10 mm each) and one size; simulate's and fit's
// single figure keeps its own scale.
TEST(EnfaceFigure, FiguresDrawnTogetherShareTheHighestScaleAndOneSize) {
  const ParametricValve valve = coarseValve();
  const ValveCase& c = valve.valve_case;
  Eigen::MatrixXd lifted = c.mesh.V;
  lifted.row(valve.free_edge(valve.free_edge.size() / 4)) +=
      45.0 * closedAnnulus(c).frame.plane.normal.transpose();
  ValveMetrics flat_metrics, lifted_metrics;
  lifted_metrics.mesh_prolapse.segments = {"A1"};  // a longer title
  const std::string flat_alone = enfaceFigureSvg(c, c.mesh.V, "flat", flat_metrics);
  const std::string lifted_alone = enfaceFigureSvg(c, lifted, "lifted", lifted_metrics);
  const double own_top = scaleTop(flat_alone), lifted_top = scaleTop(lifted_alone);
  ASSERT_LT(own_top, lifted_top) << "the lifted flap raises its own scale";
  EXPECT_EQ(flat_alone.find("one scale for all"), std::string::npos);

  const std::vector<std::string> figures =
      enfaceFiguresSvg(c, {{c.mesh.V, "flat", flat_metrics}, {lifted, "lifted", lifted_metrics}});
  ASSERT_EQ(figures.size(), 2u);
  for (const std::string& svg : figures) {
    EXPECT_EQ(scaleTop(svg), lifted_top) << "the highest of the two scales";
    EXPECT_NE(svg.find(">(one scale for all 2 figures)<"), std::string::npos);
    EXPECT_EQ(figureSize(svg), figureSize(figures[1]));
  }
  EXPECT_NE(figures[0].find(">flat: closed valve from the atrium"), std::string::npos);
  EXPECT_NE(figures[1].find(">lifted: closed valve from the atrium"), std::string::npos);
  // On the lifted closure's scale the flat one's shades are darker than on its own.
  EXPECT_NE(polygonFills(figures[0]), polygonFills(flat_alone));
  EXPECT_EQ(polygonFills(figures[1]), polygonFills(lifted_alone));
}

TEST(EnfaceFigure, SimulateWritesItBesideTheClosedMesh) {
  testing::TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  const auto r = testing::runChordfit("simulate " + testing::quoted(small) + " --quiet --out " +
                                      testing::quoted(dir / "sim"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string svg = testing::readText(dir / "sim" / "enface.svg");
  EXPECT_NE(svg.find("closed valve from the atrium, orifice"), std::string::npos);
  EXPECT_NE(r.out.find("enface.svg"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace chordfit
