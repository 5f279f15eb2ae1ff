// The closed-valve-against-tracings figure (core/section_figure.h): image planes recovered
// from tracings, annulus crossings, and the figure's content. Hand-built and parametric meshes,
// no simulation.
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/annulus_plane.h"
#include "core/cohort_presets.h"
#include "core/parametric_valve.h"
#include "core/section_figure.h"
#include "core/tracing_sampler.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

constexpr double kTight = 1e-9;

using testing::occurrences;

Tracing tracingOn(const Eigen::Vector3d& origin, const Eigen::Vector3d& normal,
                  const Eigen::MatrixXd& points, int leaflet) {
  Tracing t;
  t.points = points;
  t.plane_origin = origin;
  t.plane_normal = normal;
  t.leaflet = leaflet;
  return t;
}

TEST(TracingPlanes, RecoverTheLongAxisPlanesTheTracingsWereSampledOn) {
  ValveParameters parameters;
  parameters.target_edge_mm = 3.0;
  const ValveCase valve = makeParametricValve(parameters).valve_case;
  const AnnulusFrame frame = openAnnulusFrame(valve.mesh);
  TracingSamplerOptions options;
  options.noise_mm = 0.0;
  options.dropout_fraction = 0.0;
  SeededRandom random(1);
  const std::vector<Tracing> tracings =
      sampleTracings(valve.mesh.V, valve.mesh.F, valve.mesh.leaflet, frame, options, random);
  ASSERT_GT(tracings.size(), 6u) << "several polylines per plane";

  const std::vector<ImagePlane> expected = longAxisPlanes(frame, options.planes);
  const std::vector<ImagePlane> planes = tracingPlanes(tracings, frame);
  ASSERT_EQ(planes.size(), expected.size());
  for (std::size_t i = 0; i < planes.size(); ++i) {
    EXPECT_LT((planes[i].origin - expected[i].origin).norm(), kTight) << i;
    EXPECT_LT((planes[i].normal - expected[i].normal).norm(), kTight) << i;
    EXPECT_LT((planes[i].u - expected[i].u).norm(), 1e-12) << "u = d_i, plane " << i;
    EXPECT_LT((planes[i].w - expected[i].w).norm(), 1e-12) << "w = n_AP, plane " << i;
    EXPECT_NEAR(planes[i].angle, expected[i].angle, kTight) << i;
  }
  for (const Tracing& t : tracings) {
    int on = 0;
    for (const ImagePlane& p : planes) on += tracedOnPlane(t, p) ? 1 : 0;
    EXPECT_EQ(on, 1) << "every tracing lies on exactly one plane";
  }
}

TEST(TracingPlanes, OneImagePlaneHoldsPolylinesWithDifferentOriginsInIt) {
  AnnulusFrame frame;  // centre 0, n = z, a = x, l = y
  const Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  Eigen::MatrixXd P(2, 3);
  P << 0, 0, 0, 1, 0, 0;
  const std::vector<Tracing> tracings = {
      tracingOn({0, 0, 0}, normal, P, 0), tracingOn({5, 0, -3}, normal, P, 1),
      tracingOn({0, 0.5, 0}, normal, P, 1),  // parallel, 0.5 mm away: another plane
      tracingOn({2, 0, 1}, -normal, P, 0),   // the first plane, its normal reversed
      tracingOn({0, 0, 0}, Eigen::Vector3d::UnitZ(), P, 0)};  // short axis: no "up" in it
  const std::vector<ImagePlane> planes = tracingPlanes(tracings, frame);
  ASSERT_EQ(planes.size(), 3u);
  EXPECT_TRUE(tracedOnPlane(tracings[1], planes[0]));
  EXPECT_FALSE(tracedOnPlane(tracings[2], planes[0]));
  EXPECT_TRUE(tracedOnPlane(tracings[3], planes[0])) << "a reversed normal is the same plane";
  EXPECT_LT((planes[0].w - Eigen::Vector3d::UnitZ()).norm(), kTight);
  EXPECT_LT((planes[0].u - Eigen::Vector3d::UnitX()).norm(), kTight) << "u = normal x w";
  EXPECT_NEAR(planes[0].angle, 0.0, kTight) << "the anteroposterior plane";
  EXPECT_TRUE(planes[2].u.allFinite() && planes[2].w.allFinite());
  EXPECT_NEAR(planes[2].w.dot(Eigen::Vector3d::UnitZ()), 0.0, kTight) << "w lies in the plane";
  EXPECT_NEAR(planes[2].w.norm(), 1.0, kTight);
}

// Normals rounded to 6 decimals by another tool (1e-6 apart) and origins a micrometre off the
// plane are the same plane; 0.1 degrees or 0.05 mm apart are not (tolerances 1e-3 rad, 0.01 mm).
TEST(TracingPlanes, APlaneWrittenWithRoundedNormalsIsStillOnePlane) {
  AnnulusFrame frame;
  const Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  Eigen::MatrixXd P(2, 3);
  P << 0, 0, 0, 1, 0, 0;
  const std::vector<Tracing> tracings = {
      tracingOn({0, 0, 0}, normal, P, 0),
      tracingOn({0, 0.001, 0}, Eigen::Vector3d(0, 1, 1e-6).normalized(), P, 1),
      tracingOn({0, 0, 0}, Eigen::Vector3d(0, 1, std::tan(0.1 * M_PI / 180)).normalized(), P, 1),
      tracingOn({0, 0.05, 0}, normal, P, 0)};
  const std::vector<ImagePlane> planes = tracingPlanes(tracings, frame);
  ASSERT_EQ(planes.size(), 3u);
  EXPECT_TRUE(tracedOnPlane(tracings[1], planes[0]));
  EXPECT_FALSE(tracedOnPlane(tracings[2], planes[0]));
  EXPECT_FALSE(tracedOnPlane(tracings[3], planes[0]));
}

TEST(RingCrossings, FindTheTwoHingesOfALongAxisPlane) {
  const ValveCase cone = testing::tinyConeCase();
  ImagePlane plane;  // the xz-plane: normal y, u = x, w = z
  plane.normal = Eigen::Vector3d::UnitY();
  plane.u = Eigen::Vector3d::UnitX();
  plane.w = Eigen::Vector3d::UnitZ();
  Eigen::MatrixXd hinges = ringCrossings(plane, cone.annulus_closed);
  ASSERT_EQ(hinges.rows(), 2);
  if (hinges(0, 0) > hinges(1, 0)) hinges.row(0).swap(hinges.row(1));
  EXPECT_NEAR(hinges(0, 0), -10.0, kTight);
  EXPECT_NEAR(hinges(1, 0), 10.0, kTight);
  EXPECT_NEAR(hinges(0, 1), 0.0, kTight);
  EXPECT_NEAR(hinges(1, 1), 0.0, kTight);
}

// The cone with one tracing on its anterior section (x from 10 to 6 at y = 0) and two layers:
// a seed closure 1 mm lower (dashed grey) and the fit (leaflet colours).
struct ConeWithLayers {
  ValveCase cone;
  std::vector<SectionLayer> layers;
};
ConeWithLayers coneWithATracingAndTwoLayers() {
  ConeWithLayers c{testing::tinyConeCase(), {}};
  Eigen::MatrixXd traced(3, 3);
  traced << 10, 0, 0, 8, 0, -4, 6, 0, -8;
  c.cone.tracings = {tracingOn({0, 0, 0}, Eigen::Vector3d::UnitY(), traced, 0)};
  Eigen::MatrixXd lowered = c.cone.mesh.V;
  lowered.col(2).array() -= 1.0;
  c.layers = {{"seed", lowered, "#9a9a9a", true, 1.4}, {"fit", c.cone.mesh.V, "", false, 2.0}};
  return c;
}

TEST(SectionFigureSvg, DrawsEveryLayerByLeafletTheHingesTheThresholdAndThePlaneTracings) {
  auto [cone, layers] = coneWithATracingAndTwoLayers();
  const std::string svg = caseSectionFigureSvg(cone, layers, {"cone <test>"});
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("cone &lt;test&gt;"), std::string::npos);
  EXPECT_NE(svg.find(">plane 0: 0 deg from the AP axis (anteroposterior)<"), std::string::npos);
  for (const char* label : {"seed", "fit, anterior", "fit, posterior", "closed annulus",
                            "prolapse: hinges + 2 mm", "tracing points"}) {
    EXPECT_NE(svg.find(">" + std::string(label) + "<"), std::string::npos) << label;
  }
  EXPECT_EQ(svg.find("open annulus"), std::string::npos) << "off by default";
  // The plane cuts each leaflet once: 2 seed + 2 fit polylines and the threshold line (legend
  // samples are <line>s).
  EXPECT_EQ(occurrences(svg, "<polyline"), 5u);
  EXPECT_EQ(occurrences(svg, "<circle"), 3u + 1u) << "3 tracing points and a legend ring";
  EXPECT_EQ(occurrences(svg, "stroke=\"#9a9a9a\""), 2u + 1u) << "the seed in its own colour";
  // The seed is dashed, the threshold dotted (a dashed grey threshold looked like the seed where
  // the two crossed), each in the panel and in the legend alike.
  EXPECT_EQ(occurrences(svg, "stroke-dasharray=\"4,3\""), 2u + 1u);
  EXPECT_EQ(occurrences(svg, "stroke-dasharray=\"1,2\""), 1u + 1u);
  // Tracing points are hollow rings: a black dot vanished on compare's black line.
  EXPECT_EQ(occurrences(svg, "<g fill=\"white\" stroke=\"#111111\""), 1u + 1u);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
}

// The y of each legend label (the legend's text is 11 px, #222), in the order drawn.
std::vector<double> legendRows(const std::string& svg) {
  std::vector<double> ys;
  const std::string marker = "font-size=\"11\" fill=\"#222\"";
  for (std::size_t at = svg.find(marker); at != std::string::npos; at = svg.find(marker, at + 1)) {
    const std::size_t y = svg.rfind(" y=\"", at) + 4;
    ys.push_back(std::stod(svg.substr(y, svg.find('"', y) - y)));
  }
  return ys;
}

// The legend takes the fewest rows that fit the figure and spreads its entries evenly over
// them: "tracing points" was left alone on a second row of fit's figure.
TEST(SectionFigureSvg, SpreadsTheLegendEvenlyOverTheFewestRowsThatFit) {
  auto [cone, layers] = coneWithATracingAndTwoLayers();
  // One plane: a figure 360 px wide, too narrow for the 6 entries in one or two rows.
  const std::vector<double> narrow = legendRows(caseSectionFigureSvg(cone, layers, {"cone"}));
  ASSERT_EQ(narrow.size(), 6u);
  std::map<double, int> per_row;
  for (double y : narrow) ++per_row[y];
  EXPECT_EQ(per_row.size(), 3u);
  for (const auto& [y, entries] : per_row) EXPECT_EQ(entries, 2) << "row at y " << y;

  // Three planes (the width of fit's figure): the 6 entries in one row (fit's own labels, 25
  // characters at most, fit too).
  Eigen::MatrixXd on_x(2, 3), on_diagonal(2, 3);
  on_x << 0, 9, 0, 0, 5, -8;
  on_diagonal << 5, 5, 0, 3, 3, -6;
  cone.tracings.push_back(tracingOn({0, 0, 0}, Eigen::Vector3d::UnitX(), on_x, 1));
  cone.tracings.push_back(
      tracingOn({0, 0, 0}, Eigen::Vector3d(1, -1, 0).normalized(), on_diagonal, 1));
  const std::vector<double> wide = legendRows(caseSectionFigureSvg(cone, layers, {"cone"}));
  ASSERT_EQ(wide.size(), 6u);
  for (double y : wide) EXPECT_EQ(y, wide.front());
}

TEST(SectionFigureSvg, EachPanelShowsOnlyTheTracingsOfItsPlane) {
  ValveCase cone = testing::tinyConeCase();
  Eigen::MatrixXd traced(3, 3);
  traced << 10, 0, 0, 8, 0, -4, 6, 0, -8;
  Eigen::MatrixXd elsewhere(2, 3);  // on the plane x = 0.5
  elsewhere << 0.5, 9, 0, 0.5, 5, -8;
  cone.tracings = {tracingOn({0, 0, 0}, Eigen::Vector3d::UnitY(), traced, 0),
                   tracingOn({0.5, 0, 0}, Eigen::Vector3d::UnitX(), elsewhere, 1)};
  SectionFigureOptions options;
  options.open_annulus = true;
  const std::string svg =
      caseSectionFigureSvg(cone, {{"closed", cone.mesh.V, "", false, 2.0}}, options);
  EXPECT_NE(svg.find(">plane 1: 90 deg from the AP axis<"), std::string::npos);
  EXPECT_NE(svg.find(">open annulus<"), std::string::npos);
  EXPECT_EQ(occurrences(svg, "<circle"), 3u + 2u + 1u) << "each point once, in its own panel";
}

TEST(SectionFigureSvg, IsEmptyForACaseWithoutTracings) {
  const ValveCase cone = testing::tinyConeCase();
  EXPECT_TRUE(caseSectionFigureSvg(cone, {{"fit", cone.mesh.V, "", false, 2.0}}, {}).empty());
}

}  // namespace
}  // namespace chordfit
