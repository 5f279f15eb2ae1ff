// Unit tests of the constraint kernels (xpbd_constraints.h), the material mapping
// (material.h) and the mesh topology helpers (mesh_topology.h).
#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "core/material.h"
#include "core/mesh_topology.h"
#include "core/xpbd_constraints.h"

namespace chordfit {
namespace {

using Vec3 = Eigen::Vector3d;

constexpr double kFiniteDifferenceStep = 1e-6;
constexpr double kGradientTolerance = 1e-6;

// Central finite difference of f with respect to vertex m of `points`.
template <class F>
Vec3 numericGradient(F f, std::vector<Vec3> points, int m) {
  Vec3 g;
  for (int d = 0; d < 3; ++d) {
    std::vector<Vec3> plus = points, minus = points;
    plus[m](d) += kFiniteDifferenceStep;
    minus[m](d) -= kFiniteDifferenceStep;
    g(d) = (f(plus) - f(minus)) / (2.0 * kFiniteDifferenceStep);
  }
  return g;
}

TEST(DihedralAngle, IsZeroWhenFlatAndPositiveWhenFoldedTowardTheNormal) {
  // Faces (i, j, k) and (j, i, l) in z = 0, both wound with normal +z.
  const Vec3 xi(0, 0, 0), xj(1, 0, 0), xk(0.5, 1, 0), xl(0.5, -1, 0);
  EXPECT_NEAR(dihedralAngle(xi, xj, xk, xl), 0.0, 1e-12);
  EXPECT_GT(dihedralAngle(xi, xj, xk, Vec3(0.5, -1, 0.3)), 0.0);
  EXPECT_LT(dihedralAngle(xi, xj, xk, Vec3(0.5, -1, -0.3)), 0.0);
  // Folded by 90 degrees.
  EXPECT_NEAR(dihedralAngle(xi, xj, xk, Vec3(0.5, 0, 1)), M_PI / 2, 1e-12);
}

TEST(DihedralAngle, GradientMatchesFiniteDifferences) {
  const std::vector<Vec3> p{Vec3(0.1, -0.2, 0.05), Vec3(1.2, 0.1, -0.1), Vec3(0.6, 1.1, 0.4),
                            Vec3(0.4, -0.9, 0.3)};
  Vec3 g[4];
  dihedralAngle(p[0], p[1], p[2], p[3], g);
  auto theta = [](const std::vector<Vec3>& q) { return dihedralAngle(q[0], q[1], q[2], q[3]); };
  for (int m = 0; m < 4; ++m)
    EXPECT_LT((g[m] - numericGradient(theta, p, m)).norm(), kGradientTolerance) << "vertex " << m;
}

TEST(TriangleArea, GradientMatchesFiniteDifferences) {
  const std::vector<Vec3> p{Vec3(0.1, -0.2, 0.05), Vec3(1.2, 0.1, -0.1), Vec3(0.6, 1.1, 0.4)};
  Vec3 g[3];
  EXPECT_NEAR(triangleArea(p[0], p[1], p[2], g), 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm(),
              1e-14);
  auto area = [](const std::vector<Vec3>& q) { return triangleArea(q[0], q[1], q[2]); };
  for (int m = 0; m < 3; ++m)
    EXPECT_LT((g[m] - numericGradient(area, p, m)).norm(), kGradientTolerance) << "vertex " << m;
}

TEST(ClosestPointOnTriangle, ReportsInteriorEdgeAndVertexRegions) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  double ba, bb, bc;
  EXPECT_EQ(closestPointOnTriangle(Vec3(0.2, 0.2, 1), a, b, c, ba, bb, bc), 0);
  EXPECT_NEAR(bb, 0.2, 1e-12);
  EXPECT_NEAR(bc, 0.2, 1e-12);
  EXPECT_EQ(closestPointOnTriangle(Vec3(0.5, -1, 0), a, b, c, ba, bb, bc), 1);
  EXPECT_NEAR(bb, 0.5, 1e-12);
  EXPECT_EQ(closestPointOnTriangle(Vec3(-1, -1, 0), a, b, c, ba, bb, bc), 2);
  EXPECT_NEAR(ba, 1.0, 1e-12);
}

TEST(ProjectDistances, InextensibleEdgeReachesRestLengthInOneProjection) {
  std::vector<double> x{0, 0, 0, 2, 0, 0};
  const std::vector<double> w{1.0, 3.0};
  std::vector<double> lambda{0.0};
  projectDistances({{0, 1, 1.0, 0.0}}, 1e4, x.data(), w.data(), lambda.data());
  EXPECT_NEAR(x[3] - x[0], 1.0, 1e-12);
  // Moves are inversely proportional to mass: vertex 1 moves 3 times as far.
  EXPECT_NEAR(-(x[3] - 2.0) / x[0], 3.0, 1e-12);
}

CordConstraint vertexCord(int vertex, double rest) {
  CordConstraint c;
  c.vertices = {vertex}, c.weights = {1.0};
  c.rest = rest;
  return c;
}

TEST(ProjectCords, SlackCordDoesNothingAndStretchedCordPullsToRestLength) {
  const std::vector<double> tips{0, 0, -10};
  const std::vector<double> w{1.0};
  std::vector<double> x{0, 0, 0}, lambda{0.0};
  projectCords({vertexCord(0, 12.0)}, 1e4, tips.data(), x.data(), w.data(), lambda.data());
  EXPECT_EQ(x[2], 0.0);
  EXPECT_EQ(lambda[0], 0.0);
  projectCords({vertexCord(0, 8.0)}, 1e4, tips.data(), x.data(), w.data(), lambda.data());
  EXPECT_NEAR(x[2], -2.0, 1e-12);
  EXPECT_LT(lambda[0], 0.0);  // pulling
}

// A cord inserting between vertices: grad_m C = b_m n, so one projection of a hard cord
// moves each vertex by b_m w_m / sum(b^2 w) times the violation and puts the insertion point
// exactly at its rest length from the tip; the unweighted vertex stays where it was.
TEST(ProjectCords, CordBetweenVerticesPullsItsPointToRestLengthSharedByWeight) {
  const std::vector<double> tips{0, 0, -10};
  const std::vector<double> w{1.0, 1.0, 1.0};
  std::vector<double> x{-1, 0, 0, 1, 0, 0, 0, 5, 0}, lambda{0.0};
  CordConstraint c;
  c.vertices = {0, 1, 2}, c.weights = {0.75, 0.25, 0.0}, c.rest = 8.0;
  const double before = std::hypot(-0.5, 10.0);  // insertion (-0.5, 0, 0)
  projectCords({c}, 1e4, tips.data(), x.data(), w.data(), lambda.data());
  const Eigen::Vector3d a(x[0], x[1], x[2]), b(x[3], x[4], x[5]);
  const Eigen::Vector3d point = 0.75 * a + 0.25 * b;
  EXPECT_NEAR((point - Eigen::Vector3d(0, 0, -10)).norm(), 8.0, 1e-12);
  // Displacements along n in the ratio b_0 : b_1 = 3 : 1, summing (weighted) to C.
  const double C = before - 8.0;
  EXPECT_NEAR((a - Eigen::Vector3d(-1, 0, 0)).norm(), 0.75 / 0.625 * C, 1e-12);
  EXPECT_NEAR((b - Eigen::Vector3d(1, 0, 0)).norm(), 0.25 / 0.625 * C, 1e-12);
  EXPECT_EQ(x[6], 0.0);
  EXPECT_EQ(x[7], 5.0);
  EXPECT_LT(lambda[0], 0.0);
}

// A cord stretched far beyond its rest length (the cohort's cords in the open state) moves its
// insertion by at most max_pull per projection, toward the same end state: a point 5 mm too
// far gets there in 20 projections of 0.25 mm, not in one jump.
TEST(ProjectCords, MaxPullLimitsEachProjectionButNotWhereTheCordEnds) {
  const std::vector<double> tips{0, 0, -10};
  const std::vector<double> w{1.0};
  std::vector<double> x{0, 0, 0}, lambda{0.0};
  const CordConstraint cord = vertexCord(0, 5.0);
  projectCords({cord}, 1e4, tips.data(), x.data(), w.data(), lambda.data(), nullptr, 0.25);
  EXPECT_NEAR(x[2], -0.25, 1e-12);
  for (int k = 1; k < 20; ++k)
    projectCords({cord}, 1e4, tips.data(), x.data(), w.data(), lambda.data(), nullptr, 0.25);
  EXPECT_NEAR(x[2], -5.0, 1e-12);
  projectCords({cord}, 1e4, tips.data(), x.data(), w.data(), lambda.data(), nullptr, 0.25);
  EXPECT_NEAR(x[2], -5.0, 1e-12);  // at rest length: nothing left to pull
}

TEST(ProjectContacts, PushesAVertexOutToTheThicknessOnItsOwnSide) {
  // Triangle in z = 0 (normal +z), vertex below it at z = -0.2 that must stay below (side -1).
  std::vector<double> x{0.2, 0.2, -0.2, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<double> w{1.0, 0.0, 0.0, 0.0};
  std::vector<double> lambda{0.0};
  ContactConstraint k;
  k.p = 0, k.a = 1, k.b = 2, k.c = 3, k.side = -1.0, k.thickness = 1.0;
  projectContacts({k}, x.data(), w.data(), lambda.data());
  EXPECT_NEAR(x[2], -1.0, 1e-12);
  EXPECT_GT(lambda[0], 0.0);
  // A vertex beyond the thickness is left alone.
  x[2] = -1.5;
  lambda[0] = 0.0;
  projectContacts({k}, x.data(), w.data(), lambda.data());
  EXPECT_EQ(x[2], -1.5);
}

TEST(ProjectAreaFloors, PushesASqueezedTriangleBackToItsFloorAndLeavesOthersAlone) {
  // Rest triangle (0,0,0), (2,0,0), (0,2,0): area 2, floor 1. Vertex 2 squeezed to y = 0.4
  // (area 0.4); vertices 0 and 1 are Dirichlet, so only vertex 2 moves, along grad A = +y.
  std::vector<double> x{0, 0, 0, 2, 0, 0, 0, 0.4, 0};
  const std::vector<double> w{0.0, 0.0, 1.0};
  AreaConstraint floor;
  floor.a = 0, floor.b = 1, floor.c = 2, floor.rest_area = 1.0;
  std::vector<double> lambda{0.0};
  projectAreaFloors({floor}, x.data(), w.data(), lambda.data());
  EXPECT_NEAR(0.5 * 2.0 * x[7], 1.0, 1e-12);  // A is linear in y here: exact in one step
  EXPECT_EQ(x[6], 0.0);
  EXPECT_EQ(x[8], 0.0);
  EXPECT_GT(lambda[0], 0.0);
  // Above its floor a triangle is not touched, bit for bit, and lambda stays 0.
  const std::vector<double> above{0, 0, 0, 2, 0, 0, 0.3, 1.7, 0.2};
  x = above;
  lambda[0] = 0.0;
  projectAreaFloors({floor}, x.data(), w.data(), lambda.data());
  EXPECT_EQ(x, above);
  EXPECT_EQ(lambda[0], 0.0);
}

TEST(ProjectAreaFloors, ReachesTheFloorWithFreeVerticesAndNeverPulls) {
  // All three vertices free; a needle triangle (area 0.05) under a floor of 0.5: repeated
  // projections (one per Gauss-Seidel sweep) converge to the floor from below, and the
  // accumulated lambda, a push, never turns negative.
  std::vector<double> x{0, 0, 0, 2, 0, 0, 1, 0.05, 0};
  const std::vector<double> w{1.0, 1.0, 1.0};
  AreaConstraint floor;
  floor.a = 0, floor.b = 1, floor.c = 2, floor.rest_area = 0.5;
  std::vector<double> lambda{0.0};
  auto area = [&] {
    return triangleArea(Vec3(x[0], x[1], x[2]), Vec3(x[3], x[4], x[5]), Vec3(x[6], x[7], x[8]));
  };
  for (int sweep = 0; sweep < 5; ++sweep) {
    projectAreaFloors({floor}, x.data(), w.data(), lambda.data());
    EXPECT_GE(lambda[0], 0.0);
  }
  EXPECT_NEAR(area(), 0.5, 1e-9);
}

TEST(ProjectDistances, AccumulatesTheConstraintImpulse) {
  std::vector<double> x{0, 0, 0, 2, 0, 0}, acc(6, 0.0);
  const std::vector<double> w{1.0, 1.0};
  std::vector<double> lambda{0.0};
  projectDistances({{0, 1, 1.0, 0.0}}, 1e4, x.data(), w.data(), lambda.data(), acc.data());
  // C was +1, shared equally by the two unit masses: lambda = -1/2. acc = grad C * lambda,
  // grad_0 C = (x0 - x1)/|x0 - x1| = (-1, 0, 0), grad_1 C = (1, 0, 0).
  EXPECT_NEAR(lambda[0], -0.5, 1e-12);
  EXPECT_NEAR(acc[0], 0.5, 1e-12);
  EXPECT_NEAR(acc[3], -0.5, 1e-12);
}

TEST(OrderByColour, ConsecutiveConstraintsOfAColourShareNoVertex) {
  // Edges of a fan around vertex 0 plus the rim: a natural order where neighbours touch.
  std::vector<DistanceConstraint> edges;
  for (int k = 1; k <= 8; ++k) edges.push_back({0, k, 1.0, 0.0});
  for (int k = 1; k <= 8; ++k) edges.push_back({k, k % 8 + 1, 1.0, 0.0});
  std::vector<DistanceConstraint> ordered = edges;
  auto vertices = [](const DistanceConstraint& c) { return std::array<int, 2>{c.i, c.j}; };
  const ColourClasses classes = orderByColour(ordered, vertices);
  ASSERT_EQ(ordered.size(), edges.size());
  // The classes cover the array in order, and no two constraints of a class share a vertex
  // (what lets the simulator split a class between threads).
  EXPECT_FALSE(classes.last_shared);
  ASSERT_EQ(classes.starts.front(), 0);
  ASSERT_EQ(classes.starts.back(), static_cast<int>(ordered.size()));
  EXPECT_GE(classes.count(), 8) << "vertex 0 is in 8 edges";
  for (int k = 0; k < classes.count(); ++k) {
    ASSERT_LT(classes.starts[k], classes.starts[k + 1]);
    std::set<int> seen;
    for (int c = classes.starts[k]; c < classes.starts[k + 1]; ++c) {
      EXPECT_TRUE(seen.insert(ordered[c].i).second) << "class " << k;
      EXPECT_TRUE(seen.insert(ordered[c].j).second) << "class " << k;
    }
  }
  // Same multiset of constraints.
  std::multiset<std::pair<int, int>> before, after;
  for (const auto& c : edges) before.insert({c.i, c.j});
  for (const auto& c : ordered) after.insert({c.i, c.j});
  EXPECT_EQ(before, after);
  // Deterministic.
  std::vector<DistanceConstraint> again = edges;
  orderByColour(again, vertices);
  for (size_t k = 0; k < again.size(); ++k) EXPECT_EQ(again[k].j, ordered[k].j);
}

TEST(OrderByColour, MoreThan64ConstraintsAtOneVertexEndInASharedLastClass) {
  std::vector<DistanceConstraint> star;
  for (int k = 1; k <= 70; ++k) star.push_back({0, k, 1.0, 0.0});
  const ColourClasses classes = orderByColour(star, [](const DistanceConstraint& c) {
    return std::array<int, 2>{c.i, c.j};
  });
  ASSERT_EQ(classes.count(), 65);
  EXPECT_TRUE(classes.last_shared);
  EXPECT_EQ(classes.starts[64], 64);
  EXPECT_EQ(classes.starts[65], 70) << "the six edges no colour was left for, together";
}

TEST(Material, SpringScaleKeepsTheMembraneModulusAndGivesPoissonOneThirdWithoutAreaTerm) {
  EXPECT_NEAR(springScale(0.0), 1.0, 1e-12);
  EXPECT_NEAR(effectivePoissonRatio(0.0), 1.0 / 3.0, 1e-12);
  for (double f : {0.05, 0.1, 0.5}) {
    const double c = springScale(f) * 3.0 / 8.0;
    EXPECT_NEAR(4.0 * c * (2.0 * c + f) / (3.0 * c + f), 1.0, 1e-12) << f;
    EXPECT_GT(effectivePoissonRatio(f), 1.0 / 3.0);
  }
}

TEST(Material, UnitConversionsAreTheDocumentedOnes) {
  EXPECT_NEAR(mmHgToMpa(100.0), 0.0133322, 1e-6);
  LeafletMaterial m;
  m.density_g_per_cm3 = 1.0;
  m.thickness_mm = 2.0;
  EXPECT_NEAR(lumpedMass(m, 3.0), 6e-3, 1e-15);  // 1 g/cm^3 * 2 mm * 3 mm^2 = 6 mm^3 = 6 mg
}

// Two triangles sharing edge (1, 2): a unit square split along its diagonal.
Eigen::MatrixXi squareFaces() {
  Eigen::MatrixXi F(2, 3);
  F << 0, 1, 2, 2, 1, 3;
  return F;
}

TEST(MeshTopology, UniqueEdgesAreSortedAndCountedOnce) {
  const Eigen::MatrixXi E = uniqueEdges(squareFaces());
  Eigen::MatrixXi expected(5, 2);
  expected << 0, 1, 0, 2, 1, 2, 1, 3, 2, 3;
  EXPECT_EQ(E, expected);
}

TEST(MeshTopology, EdgeFlapsAndBendingQuadsOfTheSharedEdge) {
  Eigen::MatrixXi E, EF, EI;
  edgeFlaps(squareFaces(), E, EF, EI);
  ASSERT_EQ(E.rows(), 5);
  // Edge (1, 2) is row 2: faces 0 and 1, opposite corners 0 (vertex 0) and 2 (vertex 3).
  EXPECT_EQ(EF(2, 0), 0);
  EXPECT_EQ(EF(2, 1), 1);
  EXPECT_EQ(EI(2, 0), 0);
  EXPECT_EQ(EI(2, 1), 2);
  EXPECT_EQ(EF(0, 1), -1);  // boundary edge
  const Eigen::MatrixXi Q = bendingQuads(squareFaces());
  ASSERT_EQ(Q.rows(), 1);
  // Edge runs 1 -> 2 in face 0's winding; k = 0 (face 0), l = 3 (face 1).
  EXPECT_EQ(Q(0, 0), 1);
  EXPECT_EQ(Q(0, 1), 2);
  EXPECT_EQ(Q(0, 2), 0);
  EXPECT_EQ(Q(0, 3), 3);
  EXPECT_EQ(nonManifoldEdgeCount(squareFaces()), 0);
}

TEST(MeshTopology, BoundaryLoopOfASquareFollowsTheWinding) {
  const auto loops = boundaryLoops(squareFaces());
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_EQ(loops[0], (std::vector<int>{0, 1, 3, 2}));
}

TEST(MeshTopology, TubeHasTwoBoundaryLoopsEvenWithFlippedFaces) {
  // A 6-sided open tube: rings 0..5 (bottom) and 6..11 (top); flip every other face.
  std::vector<Eigen::Vector3i> faces;
  for (int k = 0; k < 6; ++k) {
    const int a = k, b = (k + 1) % 6, c = 6 + k, d = 6 + (k + 1) % 6;
    faces.emplace_back(a, b, d);
    faces.emplace_back(a, c, d);  // flipped relative to (a, d, c)
  }
  Eigen::MatrixXi F(12, 3);
  for (int f = 0; f < 12; ++f) F.row(f) = faces[f].transpose();
  const auto loops = boundaryLoops(F);
  ASSERT_EQ(loops.size(), 2u);
  EXPECT_EQ(loops[0].size(), 6u);
  EXPECT_EQ(loops[1].size(), 6u);
  EXPECT_EQ(loops[0][0], 0);
  EXPECT_EQ(loops[1][0], 6);
  Eigen::MatrixXi oriented;
  EXPECT_TRUE(orientFacesConsistently(F, oriented));
  // After orientation every interior edge is used once in each direction.
  std::set<std::pair<int, int>> directed;
  for (int f = 0; f < 12; ++f)
    for (int c = 0; c < 3; ++c)
      EXPECT_TRUE(directed.insert({oriented(f, c), oriented(f, (c + 1) % 3)}).second);
  EXPECT_EQ(faceComponents(F).maxCoeff(), 0);
}

// Two triangles sharing only vertex 2 (a bowtie), a separate triangle, a vertex in no face: the
// bowtie is one piece through its vertex, two through its edges.
TEST(MeshTopology, VertexComponentsJoinPiecesThatShareAVertex) {
  Eigen::MatrixXi F(3, 3);
  F << 0, 1, 2, 2, 3, 4, 5, 6, 7;
  const Eigen::VectorXi C = vertexComponents(F, 9);
  EXPECT_EQ(C, (Eigen::VectorXi(9) << 0, 0, 0, 0, 0, 1, 1, 1, 2).finished());
  EXPECT_EQ(faceComponents(F), (Eigen::VectorXi(3) << 0, 1, 2).finished());
}

TEST(MeshTopology, VertexAdjacencyListsNeighboursInOrder) {
  const auto adjacency = vertexAdjacency(squareFaces(), 4);
  EXPECT_EQ(adjacency[1], (std::vector<int>{0, 2, 3}));
  EXPECT_EQ(adjacency[0], (std::vector<int>{1, 2}));
  const auto faces = vertexFaces(squareFaces(), 4);
  EXPECT_EQ(faces[2], (std::vector<int>{0, 1}));
}

}  // namespace
}  // namespace chordfit
