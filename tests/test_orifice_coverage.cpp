// Orifice coverage (core/orifice_coverage.h): the leaflets' en-face projection against the
// area the closed annulus encloses, on known geometries.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/orifice_coverage.h"

namespace chordfit {
namespace {

constexpr double kRadius = 10.0;  // mm
constexpr int kRingVertices = 64;

// A flat fan in z = `height`: centre vertex 0, ring vertices 1..n on a circle of kRadius.
struct Fan {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Eigen::MatrixXd ring;
};

Fan flatFan(double height = 0.0) {
  Fan fan;
  fan.V.resize(kRingVertices + 1, 3);
  fan.V.row(0) << 0.0, 0.0, height;
  fan.ring.resize(kRingVertices, 3);
  for (int k = 0; k < kRingVertices; ++k) {
    const double phi = 2.0 * M_PI * k / kRingVertices;
    fan.V.row(k + 1) << kRadius * std::cos(phi), kRadius * std::sin(phi), height;
    fan.ring.row(k) << kRadius * std::cos(phi), kRadius * std::sin(phi), 0.0;
  }
  fan.F.resize(kRingVertices, 3);
  for (int k = 0; k < kRingVertices; ++k) fan.F.row(k) << 0, k + 1, (k + 1) % kRingVertices + 1;
  return fan;
}

// Keeps the faces whose centroid satisfies `keep`.
template <typename Keep>
Eigen::MatrixXi facesWhere(const Fan& fan, Keep keep) {
  std::vector<int> rows;
  for (int f = 0; f < fan.F.rows(); ++f) {
    const Eigen::Vector3d centroid =
        (fan.V.row(fan.F(f, 0)) + fan.V.row(fan.F(f, 1)) + fan.V.row(fan.F(f, 2))) / 3.0;
    if (keep(centroid)) rows.push_back(f);
  }
  Eigen::MatrixXi F(static_cast<Eigen::Index>(rows.size()), 3);
  for (size_t r = 0; r < rows.size(); ++r) F.row(r) = fan.F.row(rows[r]);
  return F;
}

TEST(OrificeCoverage, ALeafletSheetSpanningTheRingClosesTheOrifice) {
  const Fan fan = flatFan();
  const OrificeCoverage c = orificeCoverage(fan.ring, fan.V, fan.F, AnnulusFrame{}, 0.1);
  // Samples on the ring itself may fall either side of it in floating point.
  EXPECT_GT(c.coverage(), 0.9995);
  // The 64-gon's area, to the sampling's resolution.
  const double polygon_area = 0.5 * kRingVertices * kRadius * kRadius * std::sin(2 * M_PI / 64);
  EXPECT_NEAR(c.orifice_area_mm2, polygon_area, 0.01 * polygon_area);
}

TEST(OrificeCoverage, HeightDoesNotMatterOnlyTheEnFaceProjection) {
  const Fan lifted = flatFan(5.0);  // a sheet 5 mm above the ring still covers it en face
  EXPECT_GT(orificeCoverage(lifted.ring, lifted.V, lifted.F, AnnulusFrame{}).coverage(), 0.999);
}

TEST(OrificeCoverage, AMissingHalfLeavesHalfTheOrificeOpen) {
  const Fan fan = flatFan();
  const Eigen::MatrixXi half = facesWhere(fan, [](const Eigen::Vector3d& c) { return c.x() > 0; });
  const OrificeCoverage c = orificeCoverage(fan.ring, fan.V, half, AnnulusFrame{}, 0.1);
  EXPECT_NEAR(c.coverage(), 0.5, 0.01);
  EXPECT_NEAR(c.open_area_mm2, 0.5 * c.orifice_area_mm2, 0.01 * c.orifice_area_mm2);
}

// Two "leaflets", the squares of a 0.5 mm grid at x <= -1 and at x >= 1: a 2 mm slit across
// the ring.
struct Sheet {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
};

Sheet twoLeafletsWithASlit() {
  constexpr double kStep = 0.5;
  const int n = static_cast<int>(2 * (kRadius + 1) / kStep) + 1;
  Sheet sheet;
  sheet.V.resize(n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      sheet.V.row(j * n + i) << -kRadius - 1 + i * kStep, -kRadius - 1 + j * kStep, 0.0;
  std::vector<Eigen::Vector3i> faces;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const double x0 = sheet.V(j * n + i, 0), x1 = x0 + kStep;
      if (x1 > -1.0 && x0 < 1.0) continue;
      const int a = j * n + i, b = a + 1, c = a + n + 1, d = a + n;
      faces.emplace_back(a, b, c);
      faces.emplace_back(a, c, d);
    }
  sheet.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) sheet.F.row(f) = faces[f].transpose();
  return sheet;
}

// Area of the ring's disc between x = -h and x = h: 2 * integral_{-h}^{h} sqrt(R^2 - x^2) dx.
double slitArea(double h) {
  return 2.0 *
         (h * std::sqrt(kRadius * kRadius - h * h) + kRadius * kRadius * std::asin(h / kRadius));
}

TEST(OrificeCoverage, ASlitBetweenTwoLeafletsIsItsArea) {
  const Sheet sheet = twoLeafletsWithASlit();
  const Fan fan = flatFan();
  const OrificeCoverage c = orificeCoverage(fan.ring, sheet.V, sheet.F, AnnulusFrame{}, 0.05);
  EXPECT_NEAR(c.open_area_mm2, slitArea(1.0), 0.03 * slitArea(1.0));
  EXPECT_EQ(c.tissue_radius_mm, 0.0);
}

// The mesh is a mid-surface: with the tissue half a thickness to either side, the slit
// narrows by the thickness, and mid-surfaces one thickness apart (coapting leaflets, as
// contact keeps them) leave nothing open.
TEST(OrificeCoverage, TissueThicknessNarrowsTheSlitBetweenMidSurfaces) {
  const Sheet sheet = twoLeafletsWithASlit();
  const Fan fan = flatFan();
  const OrificeCoverage half =
      orificeCoverage(fan.ring, sheet.V, sheet.F, AnnulusFrame{}, 0.05, 0.5);
  EXPECT_EQ(half.tissue_radius_mm, 0.5);
  // Samples exactly on the grown edges count as covered: the sampled slit is one grid step
  // (0.05 mm) narrower than 1 mm.
  EXPECT_NEAR(half.open_area_mm2, slitArea(0.475), 0.02 * slitArea(0.475));
  const OrificeCoverage touching =
      orificeCoverage(fan.ring, sheet.V, sheet.F, AnnulusFrame{}, 0.05, 1.0);
  EXPECT_GT(touching.coverage(), 0.9995);
  // A sheet spanning the ring is not covered any further beyond it: the orifice is the ring's.
  const OrificeCoverage spanning =
      orificeCoverage(fan.ring, fan.V, fan.F, AnnulusFrame{}, 0.1, 2.0);
  EXPECT_NEAR(spanning.orifice_area_mm2,
              orificeCoverage(fan.ring, fan.V, fan.F, AnnulusFrame{}, 0.1).orifice_area_mm2, 1e-9);
}

TEST(OrificeCoverage, FrameAxesDecideTheProjectionPlane) {
  // Seen along x instead of z the flat sheet is a line: it covers nothing of a ring in the
  // y-z plane.
  Fan fan = flatFan();
  Eigen::MatrixXd ring(kRingVertices, 3);
  for (int k = 0; k < kRingVertices; ++k) {
    const double phi = 2.0 * M_PI * k / kRingVertices;
    ring.row(k) << 0.0, kRadius * std::cos(phi), kRadius * std::sin(phi);
  }
  AnnulusFrame side;
  side.plane.normal = Eigen::Vector3d::UnitX();
  side.a = Eigen::Vector3d::UnitY();
  side.l = Eigen::Vector3d::UnitZ();
  const OrificeCoverage c = orificeCoverage(ring, fan.V, fan.F, side, 0.1);
  EXPECT_LT(c.coverage(), 0.05);
}

TEST(OrificeCoverage, AHugeRingCoarsensTheGridInsteadOfExhaustingMemory) {
  Fan fan = flatFan();
  fan.V *= 1e4;  // a 100 m valve: 1.6e11 samples at 0.25 mm
  fan.ring *= 1e4;
  const OrificeCoverage c = orificeCoverage(fan.ring, fan.V, fan.F, AnnulusFrame{});
  EXPECT_LE(c.samples, 4'000'000);
  EXPECT_GT(c.coverage(), 0.999);
  EXPECT_NEAR(c.orifice_area_mm2, M_PI * 1e10, 0.01 * M_PI * 1e10);
}

TEST(OrificeCoverage, DegenerateInputGivesNoSamplesNotACrash) {
  const Fan fan = flatFan();
  EXPECT_TRUE(
      std::isnan(orificeCoverage(Eigen::MatrixXd(0, 3), fan.V, fan.F, AnnulusFrame{}).coverage()));
  EXPECT_EQ(orificeCoverage(fan.ring, fan.V, fan.F, AnnulusFrame{}, 0.0).samples, 0);
  Eigen::MatrixXd nan_ring = fan.ring;
  nan_ring(3, 1) = NAN;
  EXPECT_EQ(orificeCoverage(nan_ring, fan.V, fan.F, AnnulusFrame{}).samples, 0);
  EXPECT_DOUBLE_EQ(
      orificeCoverage(fan.ring, fan.V, Eigen::MatrixXi(0, 3), AnnulusFrame{}).coverage(), 0.0);
}

}  // namespace
}  // namespace chordfit
