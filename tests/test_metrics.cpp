#include <Eigen/Geometry>
#include <cmath>

#include <gtest/gtest.h>

#include "core/metrics.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

constexpr double kTolerance = 1e-9;

// Unit square in z = 0 as two triangles.
void unitSquare(Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  V.resize(4, 3);
  V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  F.resize(2, 3);
  F << 0, 1, 2, 0, 2, 3;
}

// Two unit squares 1 mm apart: leaflet 0 in z = 0, leaflet 1 in z = 1.
void twoLeafletSquares(Eigen::MatrixXd& V, Eigen::MatrixXi& F, Eigen::VectorXi& face_leaflet) {
  V.resize(8, 3);
  V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1;
  F.resize(4, 3);
  F << 0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7;
  face_leaflet.resize(4);
  face_leaflet << 0, 0, 1, 1;
}

TEST(OwnLeafletDistance, MeasuresEachPointToItsOwnLeafletOnly) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Eigen::VectorXi face_leaflet;
  twoLeafletSquares(V, F, face_leaflet);
  // The same point 0.1 above leaflet 0, four labels.
  Eigen::MatrixXd points(4, 3);
  points << 0.5, 0.5, 0.1, 0.5, 0.5, 0.1, 0.5, 0.5, 0.1, 0.5, 0.5, 0.1;
  Eigen::VectorXi labels(4);
  labels << 0, 1, -1, 7;  // own, the other leaflet, unlabelled, a label no face carries
  const Eigen::VectorXd own = pointToOwnLeafletDistances(V, F, face_leaflet, points, labels);
  const Eigen::VectorXd any = pointToSurfaceDistances(V, F, points);
  ASSERT_EQ(own.size(), 4);
  EXPECT_NEAR(own(0), 0.1, kTolerance);
  EXPECT_NEAR(own(1), 0.9, kTolerance);  // must reach the upper square
  EXPECT_NEAR(own(2), 0.1, kTolerance);  // whole mesh
  EXPECT_NEAR(own(3), 0.1, kTolerance);  // whole mesh
  for (int i = 0; i < 4; ++i) EXPECT_GE(own(i), any(i) - kTolerance);
}

// Table 1's last column says where the planes prolapse (a bare "Yes" on a normal valve read as
// "it prolapses"), and a '|' in a label does not split its cell.
TEST(Table1, RowsNameTheProlapseSegmentsAndEscapeABarInTheLabel) {
  ValveMetrics m;
  m.has_tracings = true;
  m.area_mm2 = 900.0;
  m.deviation.min = m.deviation.median = m.deviation.max = m.deviation.mean = m.deviation.sd = 0.5;
  m.prolapse_reconstructed = true;
  EXPECT_EQ(table1Row("normal", m),
            "| normal | 900 | 0.50 | 0.50 | 0.50 | 0.50 ± 0.50 | Yes (none) |\n");
  m.prolapse_reconstructed = false;
  m.section_prolapse.segments = {"P1", "P2"};
  m.tracing_prolapse.segments = {"P2"};
  EXPECT_EQ(table1Row("a|b", m),
            "| a\\|b | 900 | 0.50 | 0.50 | 0.50 | 0.50 ± 0.50 | No (mesh P1, P2; tracings P2) |\n");
}

TEST(SurfaceArea, OfAUnitSquareIsOne) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  unitSquare(V, F);
  EXPECT_NEAR(surfaceArea(V, F), 1.0, kTolerance);
}

TEST(SurfaceArea, OfTheConeFrustumMatchesTheTrapezoidFormula) {
  // Each of the 8 sides is two triangles; sum = exact polyhedral area, computed by hand as
  // sum over quads of the two triangles' areas.
  const ValveCase c = testing::tinyConeCase();
  double expected = 0.0;
  for (Eigen::Index f = 0; f < c.mesh.F.rows(); ++f) {
    const Eigen::Vector3d a = c.mesh.V.row(c.mesh.F(f, 0)), b = c.mesh.V.row(c.mesh.F(f, 1)),
                          d = c.mesh.V.row(c.mesh.F(f, 2));
    expected += 0.5 * (b - a).cross(d - a).norm();
  }
  EXPECT_NEAR(surfaceArea(c.mesh.V, c.mesh.F), expected, kTolerance);
  // Sanity: between the lateral areas of the inscribed and circumscribed frusta.
  const double slant = std::sqrt(8.0 * 8.0 + 4.0 * 4.0);
  EXPECT_LT(surfaceArea(c.mesh.V, c.mesh.F), M_PI * (10.0 + 6.0) * slant);
}

TEST(Deviation, StatisticsOfPointsAboveASquareAreTheirHeights) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  unitSquare(V, F);
  Eigen::MatrixXd points(4, 3);
  points << 0.5, 0.5, 0.1, 0.2, 0.7, -0.4, 0.9, 0.1, 0.3, 0.5, 0.5, 1.0;
  const DeviationStats s = summarizeDeviation(pointToSurfaceDistances(V, F, points));
  EXPECT_EQ(s.count, 4);
  EXPECT_NEAR(s.min, 0.1, kTolerance);
  EXPECT_NEAR(s.max, 1.0, kTolerance);
  EXPECT_NEAR(s.median, 0.35, kTolerance);  // mean of 0.3 and 0.4
  EXPECT_NEAR(s.mean, 0.45, kTolerance);
  // Sample SD of {0.1, 0.4, 0.3, 1.0}: sqrt(((0.35)^2 + 0.05^2 + 0.15^2 + 0.55^2) / 3).
  EXPECT_NEAR(s.sd, std::sqrt((0.1225 + 0.0025 + 0.0225 + 0.3025) / 3.0), kTolerance);
}

TEST(Deviation, IsNaNWithoutPoints) {
  const DeviationStats s = summarizeDeviation(Eigen::VectorXd());
  EXPECT_EQ(s.count, 0);
  EXPECT_TRUE(std::isnan(s.mean));
}

// Saddle ring z = h cos(2 phi), r = 15, frame n = +z, a = +x.
struct SaddleCase {
  ValveCase c;
  double h = 3.0;
};

SaddleCase saddle() {
  SaddleCase s;
  const int n = 96;  // a multiple of 4: horns and troughs fall on ring vertices
  ValveMesh& mesh = s.c.mesh;
  mesh.V.resize(n + 1, 3);
  mesh.leaflet.resize(n + 1);
  mesh.annulus.resize(n);
  for (int i = 0; i < n; ++i) {
    const double phi = 2.0 * M_PI * i / n;
    mesh.V.row(i) << 15 * std::cos(phi), 15 * std::sin(phi), s.h * std::cos(2 * phi);
    mesh.leaflet(i) = (phi < M_PI / 3 || phi > 5 * M_PI / 3) ? 0 : 1;
    mesh.annulus(i) = i;
  }
  mesh.V.row(n) << 0, 0, -15;
  mesh.leaflet(n) = 1;
  s.c.annulus_closed = mesh.V.topRows(n);
  return s;
}

TEST(HeightAboveAnnulus, IsMeasuredFromTheHingeLineOfEachLongAxisPlane) {
  const SaddleCase s = saddle();
  const ClosedAnnulus annulus = closedAnnulus(s.c);
  Eigen::MatrixXd points(3, 3);
  // In the anteroposterior plane both hinges are horns at +h: reference +h everywhere.
  points.row(0) << 5.0, 0.0, s.h + 1.0;
  // In the commissural plane both hinges are troughs at -h.
  points.row(1) << 0.0, -7.0, -s.h + 0.5;
  // At a horn itself the height is zero.
  points.row(2) << 15.0, 0.0, s.h;
  const Eigen::VectorXd heights = heightAboveAnnulus(annulus.frame, annulus.ring, points);
  EXPECT_NEAR(heights(0), 1.0, 1e-6);
  EXPECT_NEAR(heights(1), 0.5, 1e-6);
  EXPECT_NEAR(heights(2), 0.0, 1e-6);
}

TEST(Prolapse, FindsTheSegmentOfPointsMoreThanTwoMillimetresAboveTheAnnulus) {
  const SaddleCase s = saddle();
  const ClosedAnnulus annulus = closedAnnulus(s.c);
  Eigen::MatrixXd points(4, 3);
  points.row(0) << -8.0, 0.0, s.h + 3.0;  // posterior, centre of P2, 3 mm up: prolapse
  points.row(1) << -8.0, 0.5, s.h + 2.5;  // P2 again
  points.row(2) << 8.0, 0.0, s.h + 1.5;   // anterior, 1.5 mm: not prolapse
  points.row(3) << 0.0, 8.0, -s.h + 1.0;  // commissural zone, below threshold
  Eigen::VectorXi leaflets(4);
  leaflets << 1, 1, 0, -1;
  const ProlapseResult result =
      prolapseOfLabelledPoints(annulus, points, leaflets, ProlapseOptions{});
  EXPECT_EQ(result.segments, std::vector<std::string>{"P2"});
  EXPECT_NEAR(result.max_height_mm, 3.0, 1e-6);
  // Highest point per segment that has points: P2 and A2 (the commissural point, label -1,
  // falls in whichever segment its angle gives and is below both).
  EXPECT_NEAR(result.segment_max_height_mm.at("P2"), 3.0, 1e-6);
  EXPECT_NEAR(result.segment_max_height_mm.at("A2"), 1.5, 1e-6);
  // Requiring three points per segment removes it.
  EXPECT_TRUE(prolapseOfLabelledPoints(annulus, points, leaflets, {2.0, 3}).segments.empty());
}

TEST(Prolapse, LocalisesALabelledPointThatCrossedTheCentreOnItsOwnLeaflet) {
  // Closed leaflets overlap past the centre at the coaptation line: an anterior tracing point
  // on the posterior side of the centre (angle ~176 deg) still belongs to A2.
  const SaddleCase s = saddle();
  const ClosedAnnulus annulus = closedAnnulus(s.c);
  Eigen::MatrixXd points(2, 3);
  points.row(0) << -3.0, 0.2, s.h + 3.0;
  points.row(1) << -3.0, -0.2, s.h + 3.0;
  Eigen::VectorXi leaflets(2);
  leaflets << 0, 0;
  EXPECT_EQ(prolapseOfLabelledPoints(annulus, points, leaflets, ProlapseOptions{}).segments,
            std::vector<std::string>{"A2"});
}

TEST(Prolapse, ClampsCommissuralTissueJustBeyondACommissureToItsEndSegment) {
  // Posterior point 5 deg into the anterior range, next to the anterolateral (+y)
  // commissure at 60 deg: P1, not flipped to the far side of the valve.
  const SaddleCase s = saddle();
  const ClosedAnnulus annulus = closedAnnulus(s.c);
  const double phi = 55.0 * M_PI / 180.0;
  const Eigen::Vector3d p(10.0 * std::cos(phi), 10.0 * std::sin(phi), 0.0);
  EXPECT_EQ(segmentName(annulus.segments, segmentOf(annulus.segments, p, 1)), "P1");
  EXPECT_EQ(segmentName(annulus.segments, segmentOf(annulus.segments, p, 0)), "A1");
}

TEST(Prolapse, LocalisesMeshVerticesByTheirOpenStatePosition) {
  SaddleCase s = saddle();
  ValveMesh& mesh = s.c.mesh;
  const Eigen::Index moving = mesh.V.rows() - 1;
  mesh.V.row(moving) << -8.0, 0.0, -5.0;  // open state: middle of the posterior leaflet (P2)
  Eigen::MatrixXd closed = mesh.V;
  closed.row(moving) << 3.0, 0.0, s.h + 3.0;  // closed: folded past the centre, 3 mm up
  EXPECT_EQ(openStateSegments(mesh)(moving), 1 * 3 + 1);
  EXPECT_EQ(prolapseOfMesh(s.c, closed).segments, std::vector<std::string>{"P2"});
}

TEST(ComputeMetrics, ReportsNoTracingsHonestly) {
  const ValveCase c = testing::tinyConeCase();
  const ValveMetrics m = computeMetrics(c, c.mesh.V);
  EXPECT_FALSE(m.has_tracings);
  EXPECT_EQ(m.deviation.count, 0);
  EXPECT_GT(m.area_mm2, 0.0);
  EXPECT_TRUE(m.mesh_prolapse.segments.empty());  // the open cone hangs below the annulus
}

// A case without a closed annulus (allowed by the closure model: the annulus stays open)
// used to read past an empty ring; its metrics are taken against the open ring.
TEST(ComputeMetrics, WithoutAClosedAnnulusUsesTheOpenRing) {
  ValveCase c = testing::tinyConeCase();
  const ValveMetrics with_ring = [&] {
    ValveCase open_ring = c;
    open_ring.annulus_closed.resize(c.mesh.annulus.size(), 3);
    for (Eigen::Index k = 0; k < c.mesh.annulus.size(); ++k)
      open_ring.annulus_closed.row(k) = c.mesh.V.row(c.mesh.annulus(k));
    return computeMetrics(open_ring, c.mesh.V);
  }();
  c.annulus_closed.resize(0, 3);
  const ValveMetrics m = computeMetrics(c, c.mesh.V);
  EXPECT_EQ(m.mesh_prolapse.max_height_mm, with_ring.mesh_prolapse.max_height_mm);
  EXPECT_EQ(m.area_mm2, with_ring.area_mm2);
}

}  // namespace
}  // namespace chordfit
