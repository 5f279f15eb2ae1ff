// The atrial (surgeon's) view of a closed valve (core/enface_figure.h) on the open parametric
// valve: content, drawing order and the tissue outline; and `simulate` writing it.
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
