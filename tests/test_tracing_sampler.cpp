// Synthetic echo tracings (core/tracing_sampler.h), the portable random numbers they use
// (core/cohort_presets.h) and the cross-section figure writer (core/svg_cross_sections.h).
// All on hand-built or parametric meshes: no simulation, fast.
#include <cmath>
#include <set>

#include <gtest/gtest.h>

#include "core/annulus_plane.h"
#include "core/cohort_presets.h"
#include "core/metrics.h"
#include "core/parametric_valve.h"
#include "core/svg_cross_sections.h"
#include "core/tracing_sampler.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

constexpr double kTight = 1e-9;

AnnulusFrame unitFrame() {
  AnnulusFrame frame;  // centre 0, n = z, a = x, l = y
  return frame;
}

double totalLength(const std::vector<Tracing>& tracings) {
  double length = 0.0;
  for (const Tracing& t : tracings) {
    for (Eigen::Index i = 1; i < t.points.rows(); ++i) {
      length += (t.points.row(i) - t.points.row(i - 1)).norm();
    }
  }
  return length;
}

int totalPoints(const std::vector<Tracing>& tracings) {
  int count = 0;
  for (const Tracing& t : tracings) count += static_cast<int>(t.points.rows());
  return count;
}

TEST(SeededRandom, SameSeedGivesTheSameSequenceAndStreamsDiffer) {
  SeededRandom a(42), b(42), c(43);
  for (int i = 0; i < 100; ++i) {
    const double x = a.gaussian();
    EXPECT_EQ(x, b.gaussian());
    EXPECT_NE(x, c.gaussian());
  }
  SeededRandom s1 = SeededRandom::stream(7, 1), s1b = SeededRandom::stream(7, 1);
  SeededRandom s2 = SeededRandom::stream(7, 2);
  const double u = s1.uniform();
  EXPECT_EQ(u, s1b.uniform());
  EXPECT_NE(u, s2.uniform());
}

TEST(SeededRandom, BoxMullerNormalsHaveUnitVarianceAndUniformsStayInRange) {
  SeededRandom random(2024);
  constexpr int kSamples = 40000;
  double sum = 0.0, sum2 = 0.0;
  for (int i = 0; i < kSamples; ++i) {
    const double z = random.gaussian();
    sum += z;
    sum2 += z * z;
    const double u = random.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
  }
  const double mean = sum / kSamples;
  const double variance = sum2 / kSamples - mean * mean;
  EXPECT_NEAR(mean, 0.0, 0.03);  // ~6 standard errors
  EXPECT_NEAR(variance, 1.0, 0.05);
  for (int i = 0; i < 1000; ++i) EXPECT_LE(std::abs(random.clampedGaussian(2.0)), 2.0);
}

TEST(LongAxisPlanes, ContainTheAxisStartAtTheAnteroposteriorPlaneAndRotateEvenly) {
  const std::vector<ImagePlane> planes = longAxisPlanes(unitFrame(), 6);
  ASSERT_EQ(planes.size(), 6u);
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const ImagePlane& p = planes[i];
    EXPECT_NEAR(p.normal.norm(), 1.0, kTight);
    EXPECT_NEAR(p.normal.dot(Eigen::Vector3d::UnitZ()), 0.0, kTight) << "contains n_AP";
    EXPECT_NEAR(p.normal.dot(p.u), 0.0, kTight);
    EXPECT_NEAR(p.angle, i * M_PI / 6.0, kTight);
  }
  EXPECT_NEAR(std::abs(planes[0].normal.dot(Eigen::Vector3d::UnitY())), 1.0, kTight)
      << "plane 0 contains the anterior axis a = x";
  EXPECT_NEAR(std::abs(planes[3].normal.dot(Eigen::Vector3d::UnitX())), 1.0, kTight)
      << "plane K/2 is the commissural plane";
}

TEST(FaceLeaflets, TakeTheMajorityLabel) {
  Eigen::MatrixXi F(3, 3);
  F << 0, 1, 2, 1, 2, 3, 2, 3, 4;
  Eigen::VectorXi labels(5);
  labels << 0, 0, 1, 1, 1;
  const Eigen::VectorXi faces = faceLeaflets(F, labels);
  EXPECT_EQ(faces(0), 0);
  EXPECT_EQ(faces(1), 1);
  EXPECT_EQ(faces(2), 1);
}

TEST(PlaneSection, CutsTheConeAlongBothLeafletsThroughTheAxis) {
  const ValveCase cone = testing::tinyConeCase();
  const Eigen::VectorXi face_leaflet = faceLeaflets(cone.mesh.F, cone.mesh.leaflet);
  // The xz-plane (normal y) cuts the anterior column at +x and a posterior one at -x.
  const std::vector<SectionPolyline> sections = planeSection(
      cone.mesh.V, cone.mesh.F, face_leaflet, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY());
  ASSERT_EQ(sections.size(), 2u);
  std::set<int> leaflets;
  for (const SectionPolyline& s : sections) {
    leaflets.insert(s.leaflet);
    ASSERT_GE(s.points.rows(), 2);
    for (Eigen::Index i = 0; i < s.points.rows(); ++i) {
      EXPECT_NEAR(s.points(i, 1), 0.0, kTight) << "points lie in the plane";
    }
    const double x0 = s.points(0, 0), x1 = s.points(s.points.rows() - 1, 0);
    const double outer = std::max(std::abs(x0), std::abs(x1));
    const double inner = std::min(std::abs(x0), std::abs(x1));
    EXPECT_NEAR(outer, 10.0, kTight) << "from the annulus";
    EXPECT_NEAR(inner, 6.0, kTight) << "to the free edge";
    EXPECT_EQ(s.leaflet, s.points(0, 0) > 0.0 ? 0 : 1) << "anterior at +x";
  }
  EXPECT_EQ(leaflets, (std::set<int>{0, 1}));
}

TEST(PlaneSection, SplitsAPolylineWhereTheLeafletChanges) {
  // Horizontal plane z = -4 cuts the cone in one closed loop through both leaflets.
  const ValveCase cone = testing::tinyConeCase();
  const Eigen::VectorXi face_leaflet = faceLeaflets(cone.mesh.F, cone.mesh.leaflet);
  const std::vector<SectionPolyline> sections = planeSection(
      cone.mesh.V, cone.mesh.F, face_leaflet, Eigen::Vector3d(0, 0, -4), Eigen::Vector3d::UnitZ());
  ASSERT_GE(sections.size(), 2u);
  for (std::size_t i = 0; i < sections.size(); ++i) {
    for (Eigen::Index r = 0; r < sections[i].points.rows(); ++r) {
      EXPECT_NEAR(sections[i].points(r, 2), -4.0, kTight);
    }
  }
  std::set<int> leaflets;
  for (const SectionPolyline& s : sections) leaflets.insert(s.leaflet);
  EXPECT_EQ(leaflets.size(), 2u);
}

TEST(ResamplePolyline, KeepsBothEndsAndSpacesPointsEvenly) {
  Eigen::MatrixXd P(3, 3);
  P << 0, 0, 0, 1, 0, 0, 2.2, 0, 0;
  const Eigen::MatrixXd R = resamplePolyline(P, 0.5);
  ASSERT_EQ(R.rows(), 6);  // 0, 0.5, 1, 1.5, 2, 2.2
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(R(i, 0), 0.5 * i, kTight);
  EXPECT_NEAR(R(5, 0), 2.2, kTight);
}

// A coarse parametric valve as a stand-in "closed" mesh: the sampler only needs a surface.
struct ValveFixture {
  ParametricValve valve;
  AnnulusFrame frame;
  ValveFixture() {
    ValveParameters p;
    p.target_edge_mm = 2.0;
    valve = makeParametricValve(p);
    frame = openAnnulusFrame(valve.valve_case.mesh);
  }
  const ValveMesh& mesh() const { return valve.valve_case.mesh; }
  std::vector<Tracing> sample(const TracingSamplerOptions& options, SeededRandom& random) const {
    return sampleTracings(mesh().V, mesh().F, mesh().leaflet, frame, options, random);
  }
};

// Sampler options on `planes` planes with in-plane noise `noise_mm` and no dropout.
TracingSamplerOptions withoutDropout(int planes, double noise_mm) {
  TracingSamplerOptions options;
  options.planes = planes;
  options.noise_mm = noise_mm;
  options.dropout_fraction = 0.0;
  return options;
}

TEST(SampleTracings, WithoutNoiseOrDropoutTracePointsLieOnTheMeshAndTheirPlanes) {
  const ValveFixture f;
  const TracingSamplerOptions options = withoutDropout(4, 0.0);
  SeededRandom random(1);
  const std::vector<Tracing> tracings = f.sample(options, random);
  ASSERT_GE(tracings.size(), 8u) << "two sides of the valve per plane";
  std::set<int> leaflets;
  for (const Tracing& t : tracings) {
    leaflets.insert(t.leaflet);
    EXPECT_NEAR(t.plane_normal.norm(), 1.0, kTight);
    EXPECT_NEAR((t.plane_origin - f.frame.plane.centre).norm(), 0.0, kTight);
    for (Eigen::Index i = 0; i < t.points.rows(); ++i) {
      EXPECT_NEAR(t.plane_normal.dot(t.points.row(i).transpose() - t.plane_origin), 0.0, 1e-9);
    }
    for (Eigen::Index i = 1; i < t.points.rows(); ++i) {
      EXPECT_LE((t.points.row(i) - t.points.row(i - 1)).norm(), options.spacing_mm + 1e-9);
    }
  }
  EXPECT_EQ(leaflets, (std::set<int>{0, 1}));
  const Eigen::VectorXd d =
      pointToSurfaceDistances(f.mesh().V, f.mesh().F, stackTracingPoints(tracings));
  EXPECT_LT(d.maxCoeff(), 1e-6);
}

TEST(SampleTracings, DropoutRemovesTheRequestedShareInContiguousGaps) {
  const ValveFixture f;
  const TracingSamplerOptions clean = withoutDropout(6, 0.0);
  TracingSamplerOptions dropped = clean;
  dropped.dropout_fraction = 0.2;
  dropped.dropout_pieces = 3;
  SeededRandom r1(5), r2(5);
  const auto full = f.sample(clean, r1);
  const auto gappy = f.sample(dropped, r2);
  const double removed = 1.0 - static_cast<double>(totalPoints(gappy)) / totalPoints(full);
  EXPECT_NEAR(removed, 0.2, 0.04);
  // Each gap splits at most one polyline into two (or removes a whole short one).
  EXPECT_LE(gappy.size(), full.size() + 3u);
  EXPECT_LT(totalLength(gappy), totalLength(full));
}

TEST(SampleTracings, NoiseIsInPlaneWithTheRequestedSigma) {
  const ValveFixture f;
  const TracingSamplerOptions options = withoutDropout(6, 0.3);
  SeededRandom random(9);
  const auto tracings = f.sample(options, random);
  for (const Tracing& t : tracings) {
    for (Eigen::Index i = 0; i < t.points.rows(); ++i) {
      EXPECT_NEAR(t.plane_normal.dot(t.points.row(i).transpose() - t.plane_origin), 0.0, 1e-9);
    }
  }
  // In-plane isotropic noise: the distance to the surface is about the noise component
  // across the section curve, |N(0, sigma^2)|, mean sigma sqrt(2 / pi) ~ 0.24 mm.
  const Eigen::VectorXd d =
      pointToSurfaceDistances(f.mesh().V, f.mesh().F, stackTracingPoints(tracings));
  EXPECT_GT(d.mean(), 0.15);
  EXPECT_LT(d.mean(), 0.3);
}

TEST(SampleTracings, SameSeedSameTracingsOtherSeedOtherNoise) {
  const ValveFixture f;
  TracingSamplerOptions options;
  options.planes = 3;
  SeededRandom a(11), b(11), c(12);
  const auto ta = f.sample(options, a);
  const auto tb = f.sample(options, b);
  const auto tc = f.sample(options, c);
  ASSERT_EQ(ta.size(), tb.size());
  for (std::size_t i = 0; i < ta.size(); ++i) EXPECT_EQ(ta[i].points, tb[i].points);
  EXPECT_NE(stackTracingPoints(ta), stackTracingPoints(tc));
}

TEST(CrossSectionsSvg, WritesOnePanelPerPlaneWithLegendAndAxes) {
  SvgSeries line{SvgSeries::Kind::kLine, {}, "#c0392b", 2.0, SvgStroke::kSolid,
                 "closed & anterior"};
  Eigen::MatrixXd P(3, 2);
  P << -10, 0, 0, -5, 10, 2;
  line.parts.push_back(P);
  SvgSeries dots{SvgSeries::Kind::kDots, {P}, "#000", 1.0, SvgStroke::kSolid, "tracings"};
  std::vector<SvgPanel> panels(4);
  for (int i = 0; i < 4; ++i) {
    panels[i].title = "plane " + std::to_string(i);
    panels[i].series = {line, dots};
  }
  SvgFigureOptions options;
  options.title = "test <figure>";
  const std::string svg = crossSectionsSvg(panels, options);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(svg.find("test &lt;figure&gt;"), std::string::npos) << "text is escaped";
  EXPECT_NE(svg.find("closed &amp; anterior"), std::string::npos);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NE(svg.find(">plane " + std::to_string(i) + "<"), std::string::npos);
  }
  std::size_t polylines = 0;
  for (std::size_t at = svg.find("<polyline"); at != std::string::npos;
       at = svg.find("<polyline", at + 1)) {
    ++polylines;
  }
  EXPECT_EQ(polylines, 4u);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
}

}  // namespace
}  // namespace chordfit
