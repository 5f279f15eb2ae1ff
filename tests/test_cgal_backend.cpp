// SurfaceDistance and countSelfIntersections against hand-computed answers.
#include <cmath>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/cgal_backend.h"

namespace chordfit {
namespace {

// Distances are a sqrt of a few products of small doubles: 1e-12 leaves room for rounding
// but catches any wrong closest feature.
constexpr double kDistanceTolerance = 1e-12;

// The triangle A = (0,0,0), B = (1,0,0), C = (0,1,0) in the z = 0 plane.
struct UnitTriangle {
  Eigen::MatrixXd V{{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}};
  Eigen::MatrixXi F{{0, 1, 2}};
};

struct RegionCase {
  const char* region;
  Eigen::Vector3d in_plane;  // query point projected to z = 0
  Eigen::Vector3d closest;   // hand-computed closest point of the triangle
};

// One query point in each of the 7 Voronoi regions of the triangle.
std::vector<RegionCase> regionCases() {
  return {
      {"vertex A", {-1.0, -2.0, 0.0}, {0.0, 0.0, 0.0}},
      {"vertex B", {2.0, -1.0, 0.0}, {1.0, 0.0, 0.0}},
      {"vertex C", {-1.0, 2.0, 0.0}, {0.0, 1.0, 0.0}},
      {"edge AB", {0.3, -2.0, 0.0}, {0.3, 0.0, 0.0}},
      {"edge AC", {-3.0, 0.4, 0.0}, {0.0, 0.4, 0.0}},
      // Foot of (1.2, 0.8) on x + y = 1: B + 0.3 (C - B) = (0.7, 0.3).
      {"edge BC", {1.2, 0.8, 0.0}, {0.7, 0.3, 0.0}},
      {"face", {0.2, 0.3, 0.0}, {0.2, 0.3, 0.0}},
  };
}

TEST(SurfaceDistance, MatchesHandComputedDistancesInAllSevenVoronoiRegionsOnBothSides) {
  const UnitTriangle tri;
  const SurfaceDistance surface(tri.V, tri.F);
  for (double height : {0.5, -0.75, 0.0}) {
    for (const RegionCase& c : regionCases()) {
      const Eigen::Vector3d p = c.in_plane + Eigen::Vector3d(0.0, 0.0, height);
      const double expected = std::sqrt((c.in_plane - c.closest).squaredNorm() + height * height);
      Eigen::Vector3d closest;
      const double d = surface.distance(p, &closest);
      EXPECT_NEAR(d, expected, kDistanceTolerance) << c.region << " at height " << height;
      EXPECT_NEAR((closest - c.closest).norm(), 0.0, kDistanceTolerance)
          << c.region << " at height " << height;
    }
  }
}

TEST(SurfaceDistance, SkipsDegenerateAndOutOfRangeTriangles) {
  Eigen::MatrixXd V{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {5, 5, 5}};
  // Face 1 is collinear (A, B, (2,0,0)); face 2 points past the vertex list.
  Eigen::MatrixXi F{{0, 1, 2}, {0, 1, 3}, {0, 1, 9}};
  const SurfaceDistance surface(V, F);
  EXPECT_NEAR(surface.distance(Eigen::Vector3d(0.2, 0.3, 2.0)), 2.0, kDistanceTolerance);
}

TEST(SurfaceDistance, EmptySurfaceIsInfinitelyFarAway) {
  const SurfaceDistance surface(Eigen::MatrixXd(0, 3), Eigen::MatrixXi(0, 3));
  Eigen::Vector3d closest;
  EXPECT_TRUE(std::isinf(surface.distance(Eigen::Vector3d::Zero(), &closest)));
  EXPECT_TRUE(closest.array().isNaN().all());
}

// A closed, consistently oriented icosahedron with circumradius sqrt(1 + t^2).
void icosahedron(Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  V = Eigen::MatrixXd{{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                      {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  F = Eigen::MatrixXi{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                      {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                      {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                      {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
}

TEST(SurfaceDistance, GivesTheSameAnswersFromSeveralThreadsAtOnce) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  icosahedron(V, F);
  const SurfaceDistance surface(V, F);
  constexpr int kQueries = 2000;
  Eigen::MatrixXd queries = Eigen::MatrixXd::Random(kQueries, 3) * 4.0;
  Eigen::VectorXd serial(kQueries);
  for (int i = 0; i < kQueries; ++i) serial(i) = surface.distance(queries.row(i).transpose());

  constexpr int kThreads = 4;
  std::vector<Eigen::VectorXd> parallel(kThreads, Eigen::VectorXd(kQueries));
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < kQueries; ++i)
        parallel[t](i) = surface.distance(queries.row(i).transpose());
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(parallel[t], serial) << "thread " << t;
}

TEST(CgalSelfIntersections, ClosedIcosahedronHasNone) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  icosahedron(V, F);
  EXPECT_EQ(countSelfIntersections(V, F), 0);
}

TEST(CgalSelfIntersections, TwoCrossingTrianglesAreOnePair) {
  Eigen::MatrixXd V{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0}};
  Eigen::MatrixXi F{{0, 1, 2}, {3, 4, 5}};
  EXPECT_EQ(countSelfIntersections(V, F), 1);
}

TEST(CgalSelfIntersections, CoplanarFoldOverAcrossASharedEdgeCounts) {
  // Both apexes lie on the same side of the shared edge AB in the same plane.
  Eigen::MatrixXd V{{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0.5, 0}};
  Eigen::MatrixXi F{{0, 1, 2}, {1, 0, 3}};
  EXPECT_EQ(countSelfIntersections(V, F), 1);
}

TEST(CgalSelfIntersections, NeighboursSharingAVertexOrEdgeDoNotCount) {
  Eigen::MatrixXd V{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.2}, {-1, -1, 0.3}};
  Eigen::MatrixXi F{{0, 1, 2}, {2, 1, 3}, {0, 4, 1}};
  EXPECT_EQ(countSelfIntersections(V, F), 0);
}

TEST(CgalSelfIntersections, NonManifoldSoupFallsBackToTheSoupVersion) {
  // Three fins on one edge (not a polygon mesh), plus a triangle that pierces fin 0 only.
  Eigen::MatrixXd V{{0, 0, 0},    {0, 0, 1},        {1, 0, 0.5},     {-1, 0.1, 0.5},
                    {0, -1, 0.5}, {0.5, -0.5, 0.4}, {0.5, 0.5, 0.4}, {0.6, 0, 0.9}};
  Eigen::MatrixXi F{{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  EXPECT_EQ(countSelfIntersections(V, F), 0);
  Eigen::MatrixXi pierced(4, 3);
  pierced << F, Eigen::RowVector3i(5, 6, 7);
  EXPECT_EQ(countSelfIntersections(V, pierced), 1);
}

TEST(CgalSelfIntersections, DegenerateTrianglesAreNotCountedAsPairs) {
  Eigen::MatrixXd V{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
  // As a polygon mesh (CGAL reports the degenerate face as the pair (f, f)) ...
  EXPECT_EQ(countSelfIntersections(V, Eigen::MatrixXi{{0, 1, 2}, {1, 0, 3}}), 0);
  // ... and as a soup (edge 0 -> 1 used twice in the same direction).
  EXPECT_EQ(countSelfIntersections(V, Eigen::MatrixXi{{0, 1, 2}, {0, 1, 3}}), 0);
}

TEST(CgalSelfIntersections, OutOfRangeIndexOrNonFiniteCoordinateGivesMinusOne) {
  Eigen::MatrixXd V{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_EQ(countSelfIntersections(V, Eigen::MatrixXi{{0, 1, 3}}), -1);
  EXPECT_EQ(countSelfIntersections(V, Eigen::MatrixXi{{0, -1, 2}}), -1);
  V(1, 0) = std::nan("");
  EXPECT_EQ(countSelfIntersections(V, Eigen::MatrixXi{{0, 1, 2}}), -1);
}

}  // namespace
}  // namespace chordfit
