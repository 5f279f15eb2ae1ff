// Tests of the parametric open-state mitral valve (core/parametric_valve.h).
#include "core/parametric_valve.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "core/diagnostics.h"
#include "core/mesh_checks.h"

// The geometric Carpentier cross-check needs core/carpentier.cpp and core/annulus_plane.cpp
// (written by another engineer). Compile it only when both sources are in the tree.
#if __has_include("core/carpentier.cpp") && __has_include("core/annulus_plane.cpp")
#define CHORDFIT_HAVE_CARPENTIER 1
#include "core/annulus_plane.h"
#include "core/carpentier.h"
#else
#define CHORDFIT_HAVE_CARPENTIER 0
#endif

namespace chordfit {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kOnSaddleTolerance = 1e-9;      // mm, analytic annulus positions
constexpr double kBelowAnnulusTolerance = 1e-9;  // mm
constexpr double kMinEdgeRatio = 0.3;            // edge length / target_edge_mm
// The longest edges run along the free edge on the flanks of the clefts, where the leaflet
// height drops ~2 mm per mm of arc (2.1-2.2 x the target with the default 0.8-deep clefts).
constexpr double kMaxEdgeRatio = 2.3;
constexpr double kMinAreaRatio = 1e-3;               // triangle area / target_edge_mm^2
constexpr double kAnteriorFractionTolerance = 0.03;  // share of annulus vertices
constexpr double kScalingTolerance = 0.25;           // relative, vertex count ratio
constexpr double kMinOrificeFraction = 0.4;          // orifice / annulus projected area
constexpr double kMaxOrificeFraction = 0.6;
constexpr double kCarpentierAgreement = 0.95;  // share of vertices

ParametricValve defaultValve() { return makeParametricValve(ValveParameters{}); }

ValveParameters withEdge(double edge) {
  ValveParameters p;
  p.target_edge_mm = edge;
  return p;
}

Eigen::Vector3d vertex(const ValveMesh& mesh, int i) { return mesh.V.row(i).transpose(); }

// Ellipse parameter phi of a point of the default saddle ellipse.
double ellipsePhi(const ValveParameters& p, const Eigen::Vector3d& q) {
  return std::atan2(q.y() / (0.5 * p.cc_diameter_mm), q.x() / (0.5 * p.ap_diameter_mm));
}

// Directed half-edge counts and undirected edge -> face counts.
struct EdgeCounts {
  std::map<std::pair<int, int>, int> directed;
  std::map<std::pair<int, int>, int> undirected;
};

EdgeCounts countEdges(const Eigen::MatrixXi& F) {
  EdgeCounts counts;
  for (int f = 0; f < F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int a = F(f, c), b = F(f, (c + 1) % 3);
      ++counts.directed[{a, b}];
      ++counts.undirected[{std::min(a, b), std::max(a, b)}];
    }
  }
  return counts;
}

// Boundary loops traced along the boundary half-edges (in face winding order).
std::vector<std::vector<int>> traceBoundaryLoops(const Eigen::MatrixXi& F) {
  const EdgeCounts counts = countEdges(F);
  std::map<int, int> next;
  for (const auto& [edge, count] : counts.directed) {
    const auto key =
        std::make_pair(std::min(edge.first, edge.second), std::max(edge.first, edge.second));
    if (counts.undirected.at(key) == 1) next[edge.first] = edge.second;
  }
  std::vector<std::vector<int>> loops;
  std::set<int> visited;
  for (const auto& [start, unused] : next) {
    if (visited.count(start)) continue;
    std::vector<int> loop;
    for (int v = start; !visited.count(v); v = next.at(v)) {
      visited.insert(v);
      loop.push_back(v);
    }
    loops.push_back(loop);
  }
  return loops;
}

// True if `loop` is the cyclic sequence `ring`, in either direction.
bool sameCycle(std::vector<int> loop, const Eigen::VectorXi& ring) {
  if (static_cast<int>(loop.size()) != ring.size() || loop.empty()) return false;
  for (int pass = 0; pass < 2; ++pass) {
    const auto it = std::find(loop.begin(), loop.end(), ring(0));
    if (it == loop.end()) return false;
    std::rotate(loop.begin(), it, loop.end());
    bool equal = true;
    for (int k = 0; k < ring.size(); ++k) equal = equal && loop[k] == ring(k);
    if (equal) return true;
    std::reverse(loop.begin(), loop.end());
  }
  return false;
}

double triangleArea(const ValveMesh& mesh, int f) {
  const Eigen::Vector3d a = vertex(mesh, mesh.F(f, 0));
  const Eigen::Vector3d b = vertex(mesh, mesh.F(f, 1));
  const Eigen::Vector3d c = vertex(mesh, mesh.F(f, 2));
  return 0.5 * (b - a).cross(c - a).norm();
}

// Shoelace area of a loop of vertices projected on the xy plane.
double projectedArea(const ValveMesh& mesh, const Eigen::VectorXi& loop) {
  double area = 0.0;
  for (int k = 0; k < loop.size(); ++k) {
    const Eigen::Vector3d p = vertex(mesh, loop(k));
    const Eigen::Vector3d q = vertex(mesh, loop((k + 1) % loop.size()));
    area += 0.5 * (p.x() * q.y() - q.x() * p.y());
  }
  return std::abs(area);
}

// Length of column k along the mesh: indices annulus[k] .. free_edge[k] are column k in
// order of arc length (documented layout of parametric_valve.cpp).
double columnLength(const ParametricValve& valve, int k) {
  const ValveMesh& mesh = valve.valve_case.mesh;
  double length = 0.0;
  for (int v = mesh.annulus(k); v < valve.free_edge(k); ++v) {
    length += (vertex(mesh, v + 1) - vertex(mesh, v)).norm();
  }
  return length;
}

// Index into the ring of the annulus vertex nearest to ellipse parameter phi.
int columnNearest(const ParametricValve& valve, const ValveParameters& p, double phi) {
  const ValveMesh& mesh = valve.valve_case.mesh;
  int best = 0;
  double best_distance = 1e300;
  for (int k = 0; k < mesh.annulus.size(); ++k) {
    const double d =
        std::abs(std::remainder(ellipsePhi(p, vertex(mesh, mesh.annulus(k))) - phi, 2.0 * kPi));
    if (d < best_distance) best_distance = d, best = k;
  }
  return best;
}

Eigen::MatrixXd circlePolyline(double radius, int count, bool clockwise) {
  Eigen::MatrixXd P(count, 3);
  for (int i = 0; i < count; ++i) {
    const double t = (clockwise ? -1.0 : 1.0) * 2.0 * kPi * i / count;
    P.row(i) << radius * std::cos(t), radius * std::sin(t), 0.0;
  }
  return P;
}

void expectValidTube(const ParametricValve& valve) {
  const ValveMesh& mesh = valve.valve_case.mesh;
  const EdgeCounts counts = countEdges(mesh.F);
  for (const auto& [edge, count] : counts.directed) {
    ASSERT_EQ(count, 1) << "half-edge " << edge.first << "->" << edge.second
                        << " repeated: not consistently oriented or not manifold";
  }
  for (const auto& [edge, count] : counts.undirected) {
    ASSERT_LE(count, 2) << "non-manifold edge " << edge.first << "-" << edge.second;
  }
  const auto loops = traceBoundaryLoops(mesh.F);
  ASSERT_EQ(loops.size(), 2u);
  const bool annulus_first = sameCycle(loops[0], mesh.annulus);
  EXPECT_TRUE(annulus_first || sameCycle(loops[1], mesh.annulus));
  EXPECT_TRUE(sameCycle(loops[annulus_first ? 1 : 0], valve.free_edge));
  const long euler = static_cast<long>(mesh.V.rows()) -
                     static_cast<long>(counts.undirected.size()) + static_cast<long>(mesh.F.rows());
  EXPECT_EQ(euler, 0);
}

TEST(ParametricValve, MeshIsAConsistentlyOrientedManifoldTube) { expectValidTube(defaultValve()); }

TEST(ParametricValve, MeshIsAValidTubeAtEveryResolution) {
  for (double edge : {0.5, 0.8, 1.0, 2.0, 3.0, 5.0, 10.0}) {
    SCOPED_TRACE("target_edge_mm = " + std::to_string(edge));
    expectValidTube(makeParametricValve(withEdge(edge)));
  }
}

TEST(ParametricValve, EveryVertexIsUsedAndTheMeshIsOneComponent) {
  const ValveMesh& mesh = defaultValve().valve_case.mesh;
  std::vector<int> parent(mesh.V.rows());
  for (int i = 0; i < mesh.V.rows(); ++i) parent[i] = i;
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  std::vector<bool> used(mesh.V.rows(), false);
  for (int f = 0; f < mesh.F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      used[mesh.F(f, c)] = true;
      parent[find(mesh.F(f, c))] = find(mesh.F(f, (c + 1) % 3));
    }
  }
  std::set<int> roots;
  for (int i = 0; i < mesh.V.rows(); ++i) {
    EXPECT_TRUE(used[i]) << "unused vertex " << i;
    roots.insert(find(i));
  }
  EXPECT_EQ(roots.size(), 1u);
}

TEST(ParametricValve, ProjectMeshChecksAcceptTheValve) {
  const ParametricValve valve = defaultValve();
  const ValveMesh& mesh = valve.valve_case.mesh;
  Diagnostics diagnostics;
  EXPECT_TRUE(checkMesh(mesh.V, mesh.F, "parametric", diagnostics));
  EXPECT_TRUE(checkAnnulusRing(mesh.F, static_cast<int>(mesh.V.rows()), mesh.annulus, "parametric",
                               "annulus", diagnostics));
  EXPECT_TRUE(diagnostics.ok());
}

TEST(ParametricValve, NoTriangleIsDegenerate) {
  for (double edge : {0.5, 1.5, 5.0}) {
    const ValveMesh& mesh = makeParametricValve(withEdge(edge)).valve_case.mesh;
    for (int f = 0; f < mesh.F.rows(); ++f) {
      EXPECT_GT(triangleArea(mesh, f), kMinAreaRatio * edge * edge) << "face " << f;
    }
  }
}

TEST(ParametricValve, EdgeLengthsStayNearTheTarget) {
  for (double edge : {0.5, 1.0, 1.5, 2.0, 4.0}) {
    const ValveMesh& mesh = makeParametricValve(withEdge(edge)).valve_case.mesh;
    const EdgeCounts counts = countEdges(mesh.F);
    double shortest = 1e300, longest = 0.0;
    for (const auto& [e, unused] : counts.undirected) {
      const double length = (vertex(mesh, e.first) - vertex(mesh, e.second)).norm();
      shortest = std::min(shortest, length);
      longest = std::max(longest, length);
    }
    EXPECT_GE(shortest, kMinEdgeRatio * edge) << "target " << edge;
    EXPECT_LE(longest, kMaxEdgeRatio * edge) << "target " << edge;
    std::printf("[ info ] edge %.2f: edge lengths / target in [%.2f, %.2f]\n", edge,
                shortest / edge, longest / edge);
  }
}

TEST(ParametricValve, AnnulusLiesOnTheSaddleEllipse) {
  const ValveParameters p;
  const ValveMesh& mesh = defaultValve().valve_case.mesh;
  for (int k = 0; k < mesh.annulus.size(); ++k) {
    const Eigen::Vector3d q = vertex(mesh, mesh.annulus(k));
    const double phi = ellipsePhi(p, q);
    const double ellipse = std::pow(q.x() / (0.5 * p.ap_diameter_mm), 2) +
                           std::pow(q.y() / (0.5 * p.cc_diameter_mm), 2);
    EXPECT_NEAR(ellipse, 1.0, kOnSaddleTolerance) << "ring " << k;
    EXPECT_NEAR(q.z(), 0.5 * p.saddle_height_mm * std::cos(2.0 * phi), kOnSaddleTolerance)
        << "ring " << k;
  }
}

TEST(ParametricValve, AnnulusDiametersAndSaddleHeightMatchTheParameters) {
  const ValveParameters p;
  const ValveMesh& mesh = defaultValve().valve_case.mesh;
  Eigen::MatrixXd ring(mesh.annulus.size(), 3);
  for (int k = 0; k < mesh.annulus.size(); ++k) ring.row(k) = mesh.V.row(mesh.annulus(k));
  const Eigen::Vector3d span = ring.colwise().maxCoeff() - ring.colwise().minCoeff();
  // Sampling tolerance: a column spacing of ~1.5 mm misses an extreme by < 0.1 mm.
  constexpr double kSpanTolerance = 0.1;
  EXPECT_NEAR(span.x(), p.ap_diameter_mm, kSpanTolerance);
  EXPECT_NEAR(span.y(), p.cc_diameter_mm, kSpanTolerance);
  EXPECT_NEAR(span.z(), p.saddle_height_mm, kSpanTolerance);
}

TEST(ParametricValve, AnnulusRunsCounterClockwiseFromTheAnteriorMidpoint) {
  const ValveMesh& mesh = defaultValve().valve_case.mesh;
  const Eigen::Vector3d first = vertex(mesh, mesh.annulus(0));
  const Eigen::Vector3d second = vertex(mesh, mesh.annulus(1));
  EXPECT_NEAR(first.y(), 0.0, 1e-12);
  EXPECT_GT(first.x(), 0.0);
  EXPECT_GT(second.y(), 0.0);  // toward the anterolateral commissure
}

TEST(ParametricValve, LeafletHeightsAtA2AndP2MatchTheParameters) {
  const ValveParameters p;
  const ParametricValve valve = defaultValve();
  const int a2 = columnNearest(valve, p, 0.0);
  const int p2 = columnNearest(valve, p, kPi);
  EXPECT_NEAR(columnLength(valve, a2), p.anterior_height_mm, p.target_edge_mm);
  EXPECT_NEAR(columnLength(valve, p2), p.posterior_height_mm, p.target_edge_mm);
}

TEST(ParametricValve, CommissuresAndCleftsAreLowerThanTheLeafletPeaks) {
  const ValveParameters p;
  const ParametricValve valve = defaultValve();
  const ValveMesh& mesh = valve.valve_case.mesh;
  const int count = static_cast<int>(mesh.annulus.size());
  // Commissural columns: where the leaflet label changes.
  for (int k = 0; k < count; ++k) {
    if (mesh.leaflet(mesh.annulus(k)) == mesh.leaflet(mesh.annulus((k + 1) % count))) continue;
    EXPECT_NEAR(columnLength(valve, k), p.commissural_height_mm, 1.0) << "column " << k;
  }
  // Posterior height profile has two interior minima (the clefts) at the height the
  // parametrisation gives them, above 0 and below the neighbouring scallop peaks.
  std::vector<double> posterior;
  for (int k = 0; k < count; ++k) {
    if (mesh.leaflet(mesh.annulus(k)) == 1) posterior.push_back(columnLength(valve, k));
  }
  int minima = 0;
  for (size_t i = 1; i + 1 < posterior.size(); ++i) {
    if (posterior[i] < posterior[i - 1] && posterior[i] <= posterior[i + 1]) {
      ++minima;
      const double cleft =
          (1.0 - p.indentation_depth) * 0.5 * (p.posterior_side_height_mm + p.posterior_height_mm);
      EXPECT_NEAR(posterior[i], cleft, 1.0);
      EXPECT_GT(posterior[i], 0.0);
      EXPECT_LT(posterior[i], p.posterior_side_height_mm);
    }
  }
  EXPECT_EQ(minima, 2);
}

TEST(ParametricValve, AnteriorLeafletCoversItsFractionOfTheAnnulus) {
  for (double fraction : {0.25, 1.0 / 3.0, 0.45}) {
    ValveParameters p;
    p.anterior_fraction = fraction;
    const ValveMesh& mesh = makeParametricValve(p).valve_case.mesh;
    int anterior = 0;
    for (int k = 0; k < mesh.annulus.size(); ++k) anterior += mesh.leaflet(mesh.annulus(k)) == 0;
    EXPECT_NEAR(static_cast<double>(anterior) / mesh.annulus.size(), fraction,
                kAnteriorFractionTolerance);
  }
}

TEST(ParametricValve, EveryColumnHasOneLeafletLabel) {
  const ParametricValve valve = defaultValve();
  const ValveMesh& mesh = valve.valve_case.mesh;
  ASSERT_EQ(mesh.leaflet.size(), mesh.V.rows());
  ASSERT_EQ(valve.segment.size(), mesh.V.rows());
  for (int k = 0; k < mesh.annulus.size(); ++k) {
    for (int v = mesh.annulus(k); v <= valve.free_edge(k); ++v) {
      EXPECT_EQ(mesh.leaflet(v), mesh.leaflet(mesh.annulus(k)));
      EXPECT_EQ(valve.segment(v) / 3, mesh.leaflet(v));
    }
  }
}

TEST(ParametricValve, LeafletsHangBelowTheAnnulus) {
  const ParametricValve valve = defaultValve();
  const ValveMesh& mesh = valve.valve_case.mesh;
  for (int k = 0; k < mesh.annulus.size(); ++k) {
    const double annulus_z = mesh.V(mesh.annulus(k), 2);
    for (int v = mesh.annulus(k) + 1; v <= valve.free_edge(k); ++v) {
      EXPECT_LE(mesh.V(v, 2), annulus_z + kBelowAnnulusTolerance) << "vertex " << v;
      EXPECT_LT(mesh.V(v, 2), mesh.V(v - 1, 2)) << "column " << k << " not descending";
    }
  }
}

TEST(ParametricValve, FaceNormalsPointTowardTheValveAxis) {
  // Chosen orientation: face normals point from the ventricular to the atrial side, i.e.
  // toward the axis of the open funnel.
  const ValveMesh& mesh = defaultValve().valve_case.mesh;
  for (int f = 0; f < mesh.F.rows(); ++f) {
    const Eigen::Vector3d a = vertex(mesh, mesh.F(f, 0));
    const Eigen::Vector3d b = vertex(mesh, mesh.F(f, 1));
    const Eigen::Vector3d c = vertex(mesh, mesh.F(f, 2));
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    const Eigen::Vector3d centroid = (a + b + c) / 3.0;
    const Eigen::Vector3d toward_axis(-centroid.x(), -centroid.y(), 0.0);
    EXPECT_GT(normal.dot(toward_axis), 0.0) << "face " << f;
  }
}

TEST(ParametricValve, OrificeIsClearlyOpen) {
  const ParametricValve valve = defaultValve();
  const ValveMesh& mesh = valve.valve_case.mesh;
  const double annulus_area = projectedArea(mesh, mesh.annulus);
  const double orifice_area = projectedArea(mesh, valve.free_edge);
  const double fraction = orifice_area / annulus_area;
  std::printf("[ info ] projected annulus %.0f mm^2, orifice %.0f mm^2 (%.0f%%)\n", annulus_area,
              orifice_area, 100.0 * fraction);
  EXPECT_GT(fraction, kMinOrificeFraction);
  EXPECT_LT(fraction, kMaxOrificeFraction);
}

TEST(ParametricValve, ClosedAnnulusIsContractedWithADeeperSaddle) {
  const ValveParameters p;
  const ParametricValve valve = defaultValve();
  const ValveMesh& mesh = valve.valve_case.mesh;
  const Eigen::MatrixXd& closed = valve.valve_case.annulus_closed;
  ASSERT_EQ(closed.rows(), mesh.annulus.size());
  ASSERT_EQ(closed.cols(), 3);
  Eigen::MatrixXd open(mesh.annulus.size(), 3);
  for (int k = 0; k < mesh.annulus.size(); ++k) open.row(k) = mesh.V.row(mesh.annulus(k));
  const Eigen::Vector3d open_span = open.colwise().maxCoeff() - open.colwise().minCoeff();
  const Eigen::Vector3d closed_span = closed.colwise().maxCoeff() - closed.colwise().minCoeff();
  EXPECT_NEAR(closed_span.x(), p.closed_contraction * open_span.x(), 1e-9);
  EXPECT_NEAR(closed_span.y(), p.closed_contraction * open_span.y(), 1e-9);
  EXPECT_GT(closed_span.z(), open_span.z());
  for (int k = 0; k < closed.rows(); ++k) {
    const double phi = ellipsePhi(p, open.row(k).transpose());
    EXPECT_NEAR(closed(k, 2), 0.5 * p.closed_saddle_height_mm * std::cos(2.0 * phi),
                kOnSaddleTolerance);
  }
}

TEST(ParametricValve, CaseMetadataIsSet) {
  const ValveCase& c = defaultValve().valve_case;
  EXPECT_EQ(c.name, "parametric-mitral");
  EXPECT_TRUE(c.tracings.empty());
  EXPECT_FALSE(c.tips.has_value());
  EXPECT_FALSE(c.cords.has_value());
  EXPECT_EQ(c.mesh.leaflet_names, (std::vector<std::string>{"anterior", "posterior"}));
}

TEST(ParametricValve, BuildIsDeterministic) {
  const ParametricValve a = defaultValve();
  const ParametricValve b = defaultValve();
  ASSERT_EQ(a.valve_case.mesh.V.rows(), b.valve_case.mesh.V.rows());
  ASSERT_EQ(a.valve_case.mesh.F.rows(), b.valve_case.mesh.F.rows());
  EXPECT_TRUE((a.valve_case.mesh.V.array() == b.valve_case.mesh.V.array()).all());
  EXPECT_TRUE((a.valve_case.mesh.F.array() == b.valve_case.mesh.F.array()).all());
  EXPECT_TRUE((a.valve_case.mesh.leaflet.array() == b.valve_case.mesh.leaflet.array()).all());
  EXPECT_TRUE((a.valve_case.annulus_closed.array() == b.valve_case.annulus_closed.array()).all());
  EXPECT_TRUE((a.segment.array() == b.segment.array()).all());
  EXPECT_TRUE((a.free_edge.array() == b.free_edge.array()).all());
}

TEST(ParametricValve, VertexCountScalesWithTheInverseSquareOfTheEdge) {
  const double coarse = makeParametricValve(withEdge(1.5)).valve_case.mesh.V.rows();
  const double fine = makeParametricValve(withEdge(1.0)).valve_case.mesh.V.rows();
  EXPECT_NEAR(fine / coarse, 2.25, kScalingTolerance * 2.25);
}

TEST(ParametricValve, BenchmarkResolutionsGiveTheirVertexCounts) {
  // target_edge_mm for the simulator benchmark sizes (~500, ~2,000, ~8,000 vertices).
  struct Size {
    double edge;
    int vertices;
  };
  constexpr double kCountTolerance = 0.05;  // relative
  for (const Size& size : {Size{1.65, 500}, Size{0.8, 2000}, Size{0.39, 8000}}) {
    const auto count = makeParametricValve(withEdge(size.edge)).valve_case.mesh.V.rows();
    EXPECT_NEAR(static_cast<double>(count), size.vertices, kCountTolerance * size.vertices)
        << "edge " << size.edge;
  }
  for (double edge : {0.39, 0.5, 0.8, 1.0, 1.5, 1.65, 2.0, 3.0}) {
    const ValveMesh& mesh = makeParametricValve(withEdge(edge)).valve_case.mesh;
    std::printf("[ info ] target_edge_mm %.2f: %ld vertices, %ld faces, %ld annulus columns\n",
                edge, static_cast<long>(mesh.V.rows()), static_cast<long>(mesh.F.rows()),
                static_cast<long>(mesh.annulus.size()));
  }
}

void expectInvalid(const ValveParameters& p, const std::string& name) {
  try {
    makeParametricValve(p);
    ADD_FAILURE() << "no exception for bad " << name;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
  }
}

TEST(ParametricValve, InvalidParametersThrowNamingTheParameter) {
  auto bad = [](auto set) {
    ValveParameters p;
    set(p);
    return p;
  };
  expectInvalid(bad([](auto& p) { p.ap_diameter_mm = 0.0; }), "ap_diameter_mm");
  expectInvalid(bad([](auto& p) { p.cc_diameter_mm = -3.0; }), "cc_diameter_mm");
  expectInvalid(bad([](auto& p) { p.cc_diameter_mm = NAN; }), "cc_diameter_mm");
  expectInvalid(bad([](auto& p) { p.saddle_height_mm = -1.0; }), "saddle_height_mm");
  expectInvalid(bad([](auto& p) { p.closed_saddle_height_mm = 30.0; }), "closed_saddle_height_mm");
  expectInvalid(bad([](auto& p) { p.closed_contraction = 0.0; }), "closed_contraction");
  expectInvalid(bad([](auto& p) { p.anterior_fraction = 0.15; }), "anterior_fraction");
  expectInvalid(bad([](auto& p) { p.anterior_fraction = 0.7; }), "anterior_fraction");
  expectInvalid(bad([](auto& p) { p.anterior_height_mm = 0.0; }), "anterior_height_mm");
  expectInvalid(bad([](auto& p) { p.posterior_height_mm = -2.0; }), "posterior_height_mm");
  expectInvalid(bad([](auto& p) { p.posterior_side_height_mm = 0.0; }), "posterior_side_height_mm");
  expectInvalid(bad([](auto& p) { p.commissural_height_mm = INFINITY; }), "commissural_height_mm");
  expectInvalid(bad([](auto& p) { p.indentation_depth = 1.0; }), "indentation_depth");
  expectInvalid(bad([](auto& p) { p.target_edge_mm = 0.1; }), "target_edge_mm");
  expectInvalid(bad([](auto& p) { p.target_edge_mm = 11.0; }), "target_edge_mm");
  expectInvalid(bad([](auto& p) { p.anterior_height_mm = 80.0; }), "anterior_height_mm");
  expectInvalid(bad([](auto& p) { p.posterior_height_mm = 60.0; }), "posterior_height_mm");
  expectInvalid(bad([](auto& p) { p.annulus_polyline = circlePolyline(15.0, 7, false); }),
                "annulus_polyline");
  expectInvalid(bad([](auto& p) {
                  Eigen::MatrixXd P = circlePolyline(15.0, 64, false);
                  P(3, 1) = NAN;
                  p.annulus_polyline = P;
                }),
                "annulus_polyline");
  expectInvalid(bad([](auto& p) { p.annulus_polyline = Eigen::MatrixXd::Zero(10, 2); }),
                "annulus_polyline");
}

TEST(ParametricValve, ErrorMessageGivesTheRangeAndTheValue) {
  ValveParameters p;
  p.target_edge_mm = 0.1;
  try {
    makeParametricValve(p);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "target_edge_mm must be in [0.2, 10], got 0.1");
  }
}

TEST(ParametricValve, UserAnnulusPolylineIsUsed) {
  constexpr double kRadius = 15.0;
  ValveParameters p;
  p.annulus_polyline = circlePolyline(kRadius, 64, false);
  const ParametricValve valve = makeParametricValve(p);
  expectValidTube(valve);
  const ValveMesh& mesh = valve.valve_case.mesh;
  const double perimeter = 64 * 2.0 * kRadius * std::sin(kPi / 64);
  EXPECT_EQ(mesh.annulus.size(), std::lround(perimeter / p.target_edge_mm));
  const double chord_sag = kRadius * (1.0 - std::cos(kPi / 64));  // polygon vs circle
  const Eigen::MatrixXd& closed = valve.valve_case.annulus_closed;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int k = 0; k < mesh.annulus.size(); ++k) centroid += vertex(mesh, mesh.annulus(k));
  centroid /= static_cast<double>(mesh.annulus.size());
  for (int k = 0; k < mesh.annulus.size(); ++k) {
    const Eigen::Vector3d q = vertex(mesh, mesh.annulus(k));
    EXPECT_NEAR(q.z(), 0.0, 1e-12);
    EXPECT_LE(q.head<2>().norm(), kRadius + 1e-9);
    EXPECT_GE(q.head<2>().norm(), kRadius - chord_sag - 1e-9);
    // Closed: contracted about the ring centroid, flat stays flat.
    const Eigen::Vector3d expected = centroid + p.closed_contraction * (q - centroid);
    EXPECT_LT((closed.row(k).transpose() - expected).head<2>().norm(), 1e-9);
    EXPECT_NEAR(closed(k, 2), 0.0, 1e-9);
  }
  // Starts at the anterior (+x) crossing and runs toward +y.
  EXPECT_NEAR(mesh.V(mesh.annulus(0), 1), 0.0, 1e-9);
  EXPECT_GT(mesh.V(mesh.annulus(0), 0), 0.0);
  EXPECT_GT(mesh.V(mesh.annulus(1), 1), 0.0);
  for (int v = 0; v < mesh.V.rows(); ++v) EXPECT_LE(mesh.V(v, 2), 1e-9);
}

TEST(ParametricValve, RepeatedClosingPointOfThePolylineIsIgnored) {
  ValveParameters open_loop, closed_loop;
  open_loop.annulus_polyline = circlePolyline(15.0, 64, false);
  Eigen::MatrixXd P(65, 3);
  P << *open_loop.annulus_polyline, open_loop.annulus_polyline->row(0);
  closed_loop.annulus_polyline = P;
  const ValveMesh& a = makeParametricValve(open_loop).valve_case.mesh;
  const ValveMesh& b = makeParametricValve(closed_loop).valve_case.mesh;
  ASSERT_EQ(a.V.rows(), b.V.rows());
  EXPECT_LT((a.V - b.V).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(ParametricValve, NonStarShapedPolylineIsRejected) {
  // A loop that doubles back: angles about its centroid do not increase monotonically.
  Eigen::MatrixXd P(12, 3);
  for (int i = 0; i < 12; ++i) {
    const double t = 2.0 * kPi * i / 12;
    const double r = (i == 4) ? 2.0 : 15.0;  // deep notch
    P.row(i) << r * std::cos(t), r * std::sin(t), 0.0;
  }
  P.row(5) << 15.0 * std::cos(2.0 * kPi * 3.5 / 12), 15.0 * std::sin(2.0 * kPi * 3.5 / 12), 0;
  ValveParameters p;
  p.annulus_polyline = P;
  expectInvalid(p, "annulus_polyline");
}

TEST(ParametricValve, ClockwisePolylineGivesTheSameValve) {
  ValveParameters ccw, cw;
  ccw.annulus_polyline = circlePolyline(15.0, 64, false);
  cw.annulus_polyline = circlePolyline(15.0, 64, true);
  const ValveMesh& a = makeParametricValve(ccw).valve_case.mesh;
  const ValveMesh& b = makeParametricValve(cw).valve_case.mesh;
  ASSERT_EQ(a.V.rows(), b.V.rows());
  EXPECT_LT((a.V - b.V).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(ParametricValve, TiltedSaddlePolylineKeepsTheFrameConvention) {
  // A saddle ellipse rotated 20 degrees about y and shifted: leaflets must hang along the
  // fitted plane's normal (toward -z side), the closed saddle must deepen.
  const ValveParameters reference;
  Eigen::MatrixXd P(40, 3);
  for (int i = 0; i < P.rows(); ++i) {
    const double phi = 2.0 * kPi * i / P.rows();
    P.row(i) << 14.0 * std::cos(phi), 17.5 * std::sin(phi), 2.5 * std::cos(2.0 * phi);
  }
  const double angle = 20.0 * kPi / 180.0;
  Eigen::Matrix3d R;
  R << std::cos(angle), 0, std::sin(angle), 0, 1, 0, -std::sin(angle), 0, std::cos(angle);
  const Eigen::RowVector3d shift(5.0, -3.0, 40.0);
  ValveParameters p;
  p.annulus_polyline = Eigen::MatrixXd((P * R.transpose()).rowwise() + shift);
  const ParametricValve valve = makeParametricValve(p);
  expectValidTube(valve);
  const ValveMesh& mesh = valve.valve_case.mesh;
  const Eigen::Vector3d n = R.col(2);
  const Eigen::Vector3d centre = shift.transpose();
  for (int k = 0; k < mesh.annulus.size(); ++k) {
    const double annulus_height = n.dot(vertex(mesh, mesh.annulus(k)) - centre);
    // 1 mm: the clefts leave 2.5 mm of leaflet, hanging at an angle.
    EXPECT_LT(n.dot(vertex(mesh, valve.free_edge(k)) - centre), annulus_height - 1.0);
  }
  EXPECT_GT(valve.segment.minCoeff(), -1);
  // Deeper closed saddle: out-of-plane spread grows by the closed/open ratio (7/5).
  double open_spread = 0.0, closed_spread = 0.0;
  for (int k = 0; k < mesh.annulus.size(); ++k) {
    open_spread = std::max(open_spread, std::abs(n.dot(vertex(mesh, mesh.annulus(k)) - centre)));
    closed_spread =
        std::max(closed_spread,
                 std::abs(n.dot(valve.valve_case.annulus_closed.row(k).transpose() - centre)));
  }
  EXPECT_NEAR(closed_spread / open_spread,
              reference.closed_saddle_height_mm / reference.saddle_height_mm, 0.05);
}

TEST(ParametricValve, EveryCarpentierSegmentIsPresentAndNumberedFromTheAnterolateralSide) {
  const ValveParameters p;
  const ParametricValve valve = defaultValve();
  const ValveMesh& mesh = valve.valve_case.mesh;
  std::vector<int> counts(6, 0);
  for (int v = 0; v < mesh.V.rows(); ++v) {
    ASSERT_GE(valve.segment(v), 0);
    ASSERT_LT(valve.segment(v), 6);
    ++counts[valve.segment(v)];
    if (valve.segment(v) == 0 || valve.segment(v) == 3) {
      EXPECT_GT(mesh.V(v, 1), 0.0) << "A1/P1 vertex " << v << " not anterolateral";
    }
    if (valve.segment(v) == 2 || valve.segment(v) == 5) {
      EXPECT_LT(mesh.V(v, 1), 0.0) << "A3/P3 vertex " << v << " not posteromedial";
    }
  }
  for (int s = 0; s < 6; ++s) EXPECT_GT(counts[s], 0) << "segment " << s << " empty";
  EXPECT_EQ(valve.segment(mesh.annulus(columnNearest(valve, p, kPi))), 4);  // P2
  EXPECT_EQ(valve.segment(mesh.annulus(0)), 1);                             // A2
}

TEST(ParametricValve, PosteriorCleftsSplitThePosteriorArcIntoEqualAngularThirds) {
  const ParametricValve valve = defaultValve();
  const ValveMesh& mesh = valve.valve_case.mesh;
  std::vector<double> angle_sum(6, 0.0);
  std::vector<int> count(6, 0);
  for (int k = 0; k < mesh.annulus.size(); ++k) {
    const Eigen::Vector3d q = vertex(mesh, mesh.annulus(k));
    double theta = std::atan2(q.y(), q.x());
    if (theta < 0.0) theta += 2.0 * kPi;
    angle_sum[valve.segment(mesh.annulus(k))] += theta;
    ++count[valve.segment(mesh.annulus(k))];
  }
  // P1 and P3 mirror each other about the x axis, P2 is centred on pi.
  EXPECT_NEAR(angle_sum[4] / count[4], kPi, 0.05);
  EXPECT_NEAR(angle_sum[3] / count[3] + angle_sum[5] / count[5], 2.0 * kPi, 0.1);
  EXPECT_NEAR(count[3], count[5], 1);
}

#if CHORDFIT_HAVE_CARPENTIER
TEST(ParametricValve, GeometricCarpentierAssignmentAgreesWithTheBuiltSegments) {
  for (const ValveParameters& p : {ValveParameters{}, withEdge(0.8), withEdge(3.0), [] {
                                     ValveParameters q;
                                     q.annulus_polyline = circlePolyline(15.0, 64, false);
                                     return q;
                                   }()}) {
    const ParametricValve valve = makeParametricValve(p);
    const ValveMesh& mesh = valve.valve_case.mesh;
    Eigen::MatrixXd ring(mesh.annulus.size(), 3);
    for (int k = 0; k < mesh.annulus.size(); ++k) ring.row(k) = mesh.V.row(mesh.annulus(k));
    const SegmentMap map = buildSegmentMap(ring, mesh, openAnnulusFrame(mesh));
    int agree = 0;
    for (int v = 0; v < mesh.V.rows(); ++v) {
      agree += segmentOf(map, vertex(mesh, v), mesh.leaflet(v)) == valve.segment(v);
    }
    const double share = static_cast<double>(agree) / mesh.V.rows();
    EXPECT_GE(share, kCarpentierAgreement) << "edge " << p.target_edge_mm;
    std::printf("[ info ] edge %.2f: geometric Carpentier agrees on %.1f%% of vertices\n",
                p.target_edge_mm, 100.0 * share);
  }
}
#endif

}  // namespace
}  // namespace chordfit
