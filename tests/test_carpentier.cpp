#include <cmath>

#include <gtest/gtest.h>

#include "core/carpentier.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

// A circular annulus of 120 vertices with the anterior leaflet on |phi| < 60 deg (one third),
// in the frame n = +z, a = +x, l = +y. The ring is the only part of the mesh that matters.
struct RingValve {
  ValveMesh mesh;
  Eigen::MatrixXd ring;
};

RingValve circularRing(bool reverse_order) {
  RingValve r;
  const int n = 120;
  r.mesh.V.resize(n + 1, 3);
  r.mesh.leaflet.resize(n + 1);
  r.mesh.annulus.resize(n);
  for (int i = 0; i < n; ++i) {
    const double phi = 2.0 * M_PI * (i + 0.5) / n;
    r.mesh.V.row(i) << 15.0 * std::cos(phi), 15.0 * std::sin(phi), 0.0;
    r.mesh.leaflet(i) = (phi < M_PI / 3.0 || phi > 5.0 * M_PI / 3.0) ? 0 : 1;
    r.mesh.annulus(i) = reverse_order ? n - 1 - i : i;
  }
  r.mesh.V.row(n) << 0.0, 0.0, -10.0;  // a leaflet point below: the atrium is at +z
  r.mesh.leaflet(n) = 1;
  r.ring.resize(n, 3);
  for (int i = 0; i < n; ++i) r.ring.row(i) = r.mesh.V.row(r.mesh.annulus(i));
  return r;
}

std::string segmentAt(const SegmentMap& map, double degrees, int leaflet) {
  const double phi = degrees * M_PI / 180.0;
  return segmentName(
      map, segmentOf(map, Eigen::Vector3d(8 * std::cos(phi), 8 * std::sin(phi), -3), leaflet));
}

class CarpentierSegments : public ::testing::TestWithParam<bool> {};

TEST_P(CarpentierSegments, NumbersThirdsFromTheAnterolateralCommissure) {
  const RingValve r = circularRing(GetParam());
  const AnnulusFrame frame = openAnnulusFrame(r.mesh);
  const SegmentMap map = buildSegmentMap(r.ring, r.mesh, frame);
  ASSERT_EQ(map.arcs.size(), 2u);
  // Anterior arc spans -60..60 deg; +y (positive angle) is anterolateral -> A1.
  EXPECT_EQ(segmentAt(map, 45, 0), "A1");
  EXPECT_EQ(segmentAt(map, 0, 0), "A2");
  EXPECT_EQ(segmentAt(map, -45, 0), "A3");
  // Posterior arc spans 60..300 deg; thirds of 80 deg each, P1 on the +y side.
  EXPECT_EQ(segmentAt(map, 100, 1), "P1");
  EXPECT_EQ(segmentAt(map, 180, 1), "P2");
  EXPECT_EQ(segmentAt(map, 260, 1), "P3");
  // Boundaries between P thirds at 140 and 220 deg.
  EXPECT_EQ(segmentAt(map, 139, 1), "P1");
  EXPECT_EQ(segmentAt(map, 141, 1), "P2");
  EXPECT_EQ(segmentAt(map, 221, 1), "P3");
}

TEST_P(CarpentierSegments, ClampsPointsJustPastTheirLeafletsCommissure) {
  const RingValve r = circularRing(GetParam());
  const SegmentMap map = buildSegmentMap(r.ring, r.mesh, openAnnulusFrame(r.mesh));
  EXPECT_EQ(segmentAt(map, 65, 0), "A1");  // anterior point a little into the posterior range
  EXPECT_EQ(segmentAt(map, 55, 1), "P1");
}

TEST_P(CarpentierSegments, UsesTheAngleWhenTheLeafletIsUnknown) {
  const RingValve r = circularRing(GetParam());
  const SegmentMap map = buildSegmentMap(r.ring, r.mesh, openAnnulusFrame(r.mesh));
  EXPECT_EQ(segmentAt(map, 10, -1), "A2");
  EXPECT_EQ(segmentAt(map, 250, -1), "P3");
}

std::string closedSegmentAt(const SegmentMap& map, double a, double l, int leaflet) {
  return segmentName(map, closedSegmentOf(map, Eigen::Vector3d(a, l, 2.0), leaflet));
}

TEST_P(CarpentierSegments, ClosedValveSegmentsAgreeWithTheAnglesAtTheAnnulus) {
  const RingValve r = circularRing(GetParam());
  const SegmentMap map = buildSegmentMap(r.ring, r.mesh, openAnnulusFrame(r.mesh));
  // Just inside the ring (radius 14.5 of 15), away from the boundaries at +-20, 140, 220 deg.
  for (double degrees : {50.0, 30.0, 0.0, -30.0, -50.0, 70.0, 100.0, 130.0, 150.0, 180.0, 210.0,
                         230.0, 260.0, 290.0}) {
    const double phi = degrees * M_PI / 180.0;
    const Eigen::Vector3d p(14.5 * std::cos(phi), 14.5 * std::sin(phi), 2.0);
    const int leaflet = std::abs(std::remainder(degrees, 360.0)) < 60.0 ? 0 : 1;
    EXPECT_EQ(segmentName(map, closedSegmentOf(map, p, leaflet)),
              segmentName(map, segmentOf(map, p, leaflet)))
        << degrees << " deg";
  }
}

TEST_P(CarpentierSegments, ClosedValveSegmentsAreStripsFromTheAnnulusToTheCoaptationLine) {
  const RingValve r = circularRing(GetParam());
  const SegmentMap map = buildSegmentMap(r.ring, r.mesh, openAnnulusFrame(r.mesh));
  // Commissures at 60 and 300 deg: the chord between them is a = 7.5, l from 13 to -13. The
  // P1/P2 boundary runs from the ring at 140 deg (-11.49, 9.64) to the chord's third point
  // (7.5, 4.33), crossing a = 0 at l = 6.43; the A1/A2 one from (14.10, 5.13) to (7.5, 4.33).
  // Points of a posterior flap billowing over the centre, in the commissural plane (a = 0):
  // P2 near the centre, P1/P3 only beyond the boundary. segmentOf's rays call them all P1/P3.
  EXPECT_EQ(closedSegmentAt(map, 0.0, 5.0, 1), "P2");
  EXPECT_EQ(closedSegmentAt(map, 0.0, -5.0, 1), "P2");
  EXPECT_EQ(segmentName(map, segmentOf(map, Eigen::Vector3d(0.0, 5.0, 2.0), 1)), "P1");
  EXPECT_EQ(closedSegmentAt(map, 0.0, 7.0, 1), "P1");
  EXPECT_EQ(closedSegmentAt(map, 0.0, -7.0, 1), "P3");
  // Past the centre toward the anterior annulus (a crossed flap): still by the strips.
  EXPECT_EQ(closedSegmentAt(map, 5.0, 1.0, 1), "P2");
  // The anterior leaflet's free edge along the chord: A2 in its middle third, A1/A3 outside.
  EXPECT_EQ(closedSegmentAt(map, 7.0, 4.0, 0), "A2");
  EXPECT_EQ(closedSegmentAt(map, 7.0, 4.8, 0), "A1");
  EXPECT_EQ(closedSegmentAt(map, 7.0, -4.8, 0), "A3");
  // An anterior point that crossed the centre to the posterior side.
  EXPECT_EQ(closedSegmentAt(map, -3.0, 0.2, 0), "A2");
  // Unlabelled points take the leaflet of their angle first.
  EXPECT_EQ(closedSegmentAt(map, -5.0, 0.0, -1), "P2");
}

INSTANTIATE_TEST_SUITE_P(RingOrder, CarpentierSegments, ::testing::Values(false, true));

}  // namespace
}  // namespace chordfit
