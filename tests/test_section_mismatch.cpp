// The stray-section measure (core/section_mismatch.h) against hand-computed integrals on a
// flat sheet cut by one plane.
#include <cmath>

#include <gtest/gtest.h>

#include "core/section_mismatch.h"

namespace chordfit {
namespace {

constexpr double kTight = 1e-9;

// A 10 x 10 mm sheet in z = 0 of 1 mm squares (two triangles each), leaflet `label`; its
// annulus is the boundary loop and stays at z = 0 when closed.
ValveCase flatSheet(int label = 0) {
  constexpr int kCells = 10;
  ValveCase c;
  c.mesh.V.resize((kCells + 1) * (kCells + 1), 3);
  for (int j = 0; j <= kCells; ++j)
    for (int i = 0; i <= kCells; ++i) c.mesh.V.row(j * (kCells + 1) + i) << i, j, 0.0;
  c.mesh.F.resize(2 * kCells * kCells, 3);
  for (int j = 0; j < kCells; ++j)
    for (int i = 0; i < kCells; ++i) {
      const int a = j * (kCells + 1) + i, b = a + 1, d = a + kCells + 1, e = d + 1;
      c.mesh.F.row(2 * (j * kCells + i)) << a, b, e;
      c.mesh.F.row(2 * (j * kCells + i) + 1) << a, e, d;
    }
  c.mesh.leaflet = Eigen::VectorXi::Constant(c.mesh.V.rows(), label);
  c.mesh.leaflet_names = {"anterior", "posterior"};
  std::vector<int> ring;
  for (int i = 0; i < kCells; ++i) ring.push_back(i);
  for (int j = 0; j < kCells; ++j) ring.push_back(j * (kCells + 1) + kCells);
  for (int i = kCells; i > 0; --i) ring.push_back(kCells * (kCells + 1) + i);
  for (int j = kCells; j > 0; --j) ring.push_back(j * (kCells + 1));
  c.mesh.annulus = Eigen::Map<Eigen::VectorXi>(ring.data(), static_cast<Eigen::Index>(ring.size()));
  c.annulus_closed.resize(c.mesh.annulus.size(), 3);
  for (Eigen::Index k = 0; k < c.mesh.annulus.size(); ++k)
    c.annulus_closed.row(k) = c.mesh.V.row(c.mesh.annulus(k));
  return c;
}

// A straight tracing on the plane y = 5 (normal +y) from x0 to x1 at height z, `leaflet`.
Tracing tracingAt(double x0, double x1, double z, int leaflet = 0) {
  Tracing t;
  constexpr int kPoints = 21;
  t.points.resize(kPoints, 3);
  for (int i = 0; i < kPoints; ++i) t.points.row(i) << x0 + (x1 - x0) * i / (kPoints - 1.0), 5, z;
  t.plane_origin = Eigen::Vector3d(0, 5, 0);
  t.plane_normal = Eigen::Vector3d::UnitY();
  t.leaflet = leaflet;
  return t;
}

// The sheet's section by y = 5 is the segment x in [0, 10] at z = 0 (length 10 mm).
double excessOf(ValveCase c, const Tracing& tracing, int leaflet = 0) {
  c.tracings = {tracing};
  const SectionMismatch mismatch(c);
  const Eigen::VectorXd E = mismatch.excess(c.mesh.V);
  EXPECT_EQ(E.size(), mismatch.termCount());
  return E(leaflet);
}

TEST(SectionMismatch, OneTermPerTracingPlaneAndLeaflet) {
  ValveCase c = flatSheet();
  c.mesh.leaflet(0) = 1;  // two leaflet labels
  Tracing other = tracingAt(0, 10, 0);
  other.plane_origin = Eigen::Vector3d(0, 2, 0);
  other.points.col(1).setConstant(2.0);
  c.tracings = {tracingAt(0, 10, 0), tracingAt(0, 10, 0), other};
  const SectionMismatch mismatch(c);
  EXPECT_EQ(mismatch.planeCount(), 2);
  EXPECT_EQ(mismatch.termCount(), 4);
  EXPECT_EQ(SectionMismatch(flatSheet()).termCount(), 0) << "no tracings, no terms";
}

TEST(SectionMismatch, ASectionWithinTheToleranceOfItsTracingCostsNothing) {
  EXPECT_EQ(excessOf(flatSheet(), tracingAt(0, 10, 0.0)), 0.0);
  EXPECT_EQ(excessOf(flatSheet(), tracingAt(0, 10, 1.4)), 0.0);
}

TEST(SectionMismatch, AParallelOffsetCostsTheSquaredExcessTimesTheLengthOverHalfAMillimetre) {
  // d = 3 mm everywhere: (3 - 1.5)^2 * 10 mm / 0.5 mm.
  EXPECT_NEAR(excessOf(flatSheet(), tracingAt(0, 10, 3.0)), 1.5 * 1.5 * 10.0 / 0.5, kTight);
  // d = 10 mm: the excess is capped at 5 mm.
  EXPECT_NEAR(excessOf(flatSheet(), tracingAt(0, 10, 10.0)), 5.0 * 5.0 * 10.0 / 0.5, kTight);
}

TEST(SectionMismatch, AnUntracedEndCostsTheIntegralOfItsStrayDistance) {
  // Traced on x in [0, 5] in the sheet: the section beyond x = 6.5 strays by x - 6.5, so
  // E = integral_0^3.5 s^2 ds / 0.5 = 3.5^3 / 1.5. The kink at 6.5 lies inside a 1 mm section
  // segment, so 3-point Gauss-Legendre is close but not exact there.
  EXPECT_NEAR(excessOf(flatSheet(), tracingAt(0, 5, 0.0)), std::pow(3.5, 3) / 1.5, 0.02);
}

TEST(SectionMismatch, OnlyTracingsOfTheSameLeafletOrUnlabelledOnesCount) {
  // A tracing of the posterior leaflet says nothing about the anterior sheet: no term.
  EXPECT_EQ(excessOf(flatSheet(0), tracingAt(0, 10, 3.0, 1)), 0.0);
  // An unlabelled tracing counts for every leaflet.
  EXPECT_NEAR(excessOf(flatSheet(0), tracingAt(0, 10, 3.0, -1)), 45.0, kTight);
  EXPECT_NEAR(excessOf(flatSheet(1), tracingAt(0, 10, 3.0, 1), 1), 45.0, kTight);
}

TEST(SectionMismatch, IsContinuousWhenAVertexCrossesThePlane) {
  ValveCase c = flatSheet();
  c.tracings = {tracingAt(0, 10, 3.0)};
  const SectionMismatch mismatch(c);
  // Lift the row y = 5 to z = 0.5 and slide vertex (5, 5) across the plane y = 5.
  Eigen::MatrixXd V = c.mesh.V;
  for (int i = 0; i <= 10; ++i) V(5 * 11 + i, 2) = 0.5;
  V(5 * 11 + 5, 1) = 5.0 - 1e-7;
  const double before = mismatch.excess(V)(0);
  V(5 * 11 + 5, 1) = 5.0 + 1e-7;
  const double after = mismatch.excess(V)(0);
  EXPECT_NEAR(before, after, 1e-5);
  EXPECT_GT(before, 0.0);
}

}  // namespace
}  // namespace chordfit
