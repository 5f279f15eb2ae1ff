// The paper's heuristic on the hand-built cone (tests/test_support.h), checked against the
// formulas worked out by hand, and the automatic placement rules on a parametric valve.
#include <cmath>
#include <set>

#include <gtest/gtest.h>

#include "core/heuristic.h"
#include "core/parametric_valve.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

constexpr double kExact = 1e-9;

// Cone free-edge vertex k sits at (6 cos(k 45deg), 6 sin(k 45deg), -8), index 8 + k.
ValveCase coneWithUserCords() {
  ValveCase c = testing::tinyConeCase();
  CordSet cords;
  cords.tips = {{"anterolateral", Eigen::Vector3d::Zero(), std::nullopt},
                {"posteromedial", Eigen::Vector3d::Zero(), std::nullopt}};
  for (const auto& [vertex, tip] : {std::pair{9, 0}, {10, 0}, {13, 1}, {14, 1}}) {
    Cord cord;
    cord.vertex = vertex;
    cord.tip = tip;
    cord.compliance = 0.0;
    cords.cords.push_back(cord);
  }
  c.cords = cords;
  return c;
}

TEST(HeuristicCordSet, TipsAreSubsetCentroidsMovedDownByTheirDistanceToThePlane) {
  const CordSet set = heuristicCordSet(coneWithUserCords());
  ASSERT_EQ(set.tips.size(), 2u);
  // Subset 0: vertices 9 = (4.2426, 4.2426, -8) and 10 = (0, 6, -8).
  // c0 = (2.1213, 5.1213, -8), d0 = 8, tip0 = c0 - 8 * (0, 0, 1) = (2.1213, 5.1213, -16).
  const double s = 6.0 * std::sqrt(0.5);
  EXPECT_NEAR(set.tips[0].position.x(), s / 2.0, kExact);
  EXPECT_NEAR(set.tips[0].position.y(), (s + 6.0) / 2.0, kExact);
  EXPECT_NEAR(set.tips[0].position.z(), -16.0, kExact);
  // Subset 1 is the mirror image through the axis: vertices 13 and 14.
  EXPECT_NEAR(set.tips[1].position.x(), -s / 2.0, kExact);
  EXPECT_NEAR(set.tips[1].position.y(), -(s + 6.0) / 2.0, kExact);
  EXPECT_NEAR(set.tips[1].position.z(), -16.0, kExact);
}

TEST(HeuristicCordSet, RestLengthIsDistanceToPlanePlusDistanceToTip) {
  const CordSet set = heuristicCordSet(coneWithUserCords());
  ASSERT_EQ(set.cords.size(), 4u);
  // Cord on vertex 9: dist to AP = 8; |V - tip0| = |(s/2, (s - 6)/2, 8)|.
  const double s = 6.0 * std::sqrt(0.5);
  const double expected = 8.0 + std::sqrt(s * s / 4.0 + (s - 6.0) * (s - 6.0) / 4.0 + 64.0);
  EXPECT_NEAR(set.cords[0].rest_length, expected, kExact);
  EXPECT_NEAR(expected, 16.3230, 1e-4);  // the hand-computed value
  // Cord on vertex 10 = (0, 6, -8): |V - tip0| = |(-s/2, (6 - s)/2, 8)|, same length by symmetry.
  EXPECT_NEAR(set.cords[1].rest_length, expected, kExact);
  for (const Cord& cord : set.cords) {
    EXPECT_EQ(cord.provenance, Provenance::kHeuristic);
    EXPECT_DOUBLE_EQ(cord.scale(), 1.0);
  }
}

TEST(HeuristicCordSet, UsesTipsGivenByTheCase) {
  ValveCase c = coneWithUserCords();
  c.tips = std::vector<PmTip>{{"anterolateral", Eigen::Vector3d(0, 4, -20), std::nullopt},
                              {"posteromedial", Eigen::Vector3d(0, -4, -20), std::nullopt}};
  const CordSet set = heuristicCordSet(c);
  EXPECT_EQ(set.tips[0].position, Eigen::Vector3d(0, 4, -20));
  // Vertex 10 = (0, 6, -8): 8 + |(0, 2, 12)|.
  EXPECT_NEAR(set.cords[1].rest_length, 8.0 + std::sqrt(4.0 + 144.0), kExact);
}

// With the case's cords, pm_tips pair with the cord set's tips by their place in the list: a
// count that does not match was ignored without a word (the formula placed the tips).
TEST(HeuristicCordSet, NamesPmTipsItCannotPairWithTheCasesCords) {
  ValveCase c = coneWithUserCords();
  EXPECT_EQ(pmTipsCountProblem(c), "") << "no pm_tips";
  c.tips = std::vector<PmTip>{{"anterolateral", Eigen::Vector3d(0, 4, -20), std::nullopt}};
  EXPECT_NE(pmTipsCountProblem(c).find("1 PM tip for the cord set's 2 tips"), std::string::npos)
      << pmTipsCountProblem(c);
  c.tips->push_back({"posteromedial", Eigen::Vector3d(0, -4, -20), std::nullopt});
  EXPECT_EQ(pmTipsCountProblem(c), "");
  c.cords.reset();
  c.tips->push_back({"third", Eigen::Vector3d(4, 0, -20), std::nullopt});
  EXPECT_EQ(pmTipsCountProblem(c), "") << "without cords, any count: each cord to its nearest";
}

TEST(SplitBySide, PutsPositiveLateralCoordinateOnTheAnterolateralTip) {
  const ValveCase c = testing::tinyConeCase();
  const AnnulusFrame frame = openAnnulusFrame(c.mesh);
  // Vertices 9, 10 have y > 0; 13, 14 have y < 0.
  EXPECT_EQ(splitBySide(c.mesh, frame, {9, 10, 13, 14}), (std::vector<int>{0, 0, 1, 1}));
}

TEST(CordScaling, ScalesOneCordAGroupOrAllAndLeavesLockedCordsAlone) {
  const ValveCase c = coneWithUserCords();
  CordSet set = heuristicCordSet(c);
  const double seed0 = set.cords[0].seed_rest_length;
  EXPECT_EQ(scaleCord(set, 0, 1.2), 1);
  EXPECT_NEAR(set.cords[0].rest_length, 1.2 * seed0, kExact);
  EXPECT_EQ(set.cords[0].provenance, Provenance::kManual);
  // Group posterior (label 1) x posteromedial (tip 1): vertices 13 and 14 are posterior.
  set.cords[3].locked = true;
  const double locked_length = set.cords[3].rest_length;
  EXPECT_EQ(scaleGroup(set, c.mesh.leaflet, 1, 1, 0.9), 1);
  EXPECT_NEAR(set.cords[2].scale(), 0.9, kExact);
  EXPECT_EQ(set.cords[3].rest_length, locked_length);
  EXPECT_EQ(scaleAllCords(set, 1.1), 3);
  EXPECT_NEAR(set.cords[0].scale(), 1.1, kExact);  // a scale multiplies the seed, not the last
  EXPECT_EQ(set.cords[3].rest_length, locked_length);
}

class AutomaticPlacement : public ::testing::Test {
 protected:
  ParametricValve valve_ = makeParametricValve(ValveParameters{});
  HeuristicOptions options_;
};

TEST_F(AutomaticPlacement, PutsPrimariesOnTheFreeEdgeAndSecondariesOnTheBelly) {
  const auto attachments = placeCordAttachments(valve_.valve_case.mesh, options_);
  std::set<int> free_edge(valve_.free_edge.data(),
                          valve_.free_edge.data() + valve_.free_edge.size());
  int primaries = 0, secondaries = 0;
  for (const CordAttachment& a : attachments) {
    if (a.kind == CordKind::kPrimary) {
      ++primaries;
      EXPECT_TRUE(free_edge.count(a.vertex)) << a.vertex;
    } else {
      ++secondaries;
      EXPECT_FALSE(free_edge.count(a.vertex)) << a.vertex;
    }
  }
  EXPECT_GT(primaries, 8);
  EXPECT_GT(secondaries, 4);
}

// Issue 3's elastic option per cord kind: the placed cords take their kind's compliance; a
// case's own cords keep theirs.
TEST_F(AutomaticPlacement, GivesEachPlacedCordItsKindsCompliance) {
  options_.primary_compliance_mm_per_n = 0.5;
  options_.secondary_compliance_mm_per_n = 1.5;
  const CordSet set = heuristicCordSet(valve_.valve_case, options_);
  ASSERT_FALSE(set.cords.empty());
  for (const Cord& cord : set.cords)
    EXPECT_EQ(cord.compliance, cord.kind == CordKind::kPrimary ? 0.5 : 1.5);
  const CordSet own = heuristicCordSet(coneWithUserCords(), options_);
  for (const Cord& cord : own.cords) EXPECT_EQ(cord.compliance, 0.0);
}

TEST_F(AutomaticPlacement, SpacesPrimariesAsAskedAlongTheFreeEdge) {
  const ValveMesh& mesh = valve_.valve_case.mesh;
  double free_edge_length = 0.0;
  for (Eigen::Index i = 0; i < valve_.free_edge.size(); ++i) {
    free_edge_length += (mesh.V.row(valve_.free_edge(i)) -
                         mesh.V.row(valve_.free_edge((i + 1) % valve_.free_edge.size())))
                            .norm();
  }
  int primaries = 0;
  for (const CordAttachment& a : placeCordAttachments(mesh, options_)) {
    primaries += a.kind == CordKind::kPrimary;
  }
  const double expected = free_edge_length / options_.primary_spacing_mm;
  EXPECT_NEAR(primaries, expected, 0.15 * expected + 1.0);
}

// A spacing of 1e-8 mm used to overflow the int count and silently place a single primary.
TEST_F(AutomaticPlacement, RefusesASpacingItsCountWouldOverflowInsteadOfPlacingOneCord) {
  HeuristicOptions tiny = options_;
  tiny.primary_spacing_mm = 1e-8;
  EXPECT_THROW(placeCordAttachments(valve_.valve_case.mesh, tiny), std::invalid_argument);
  tiny = options_;
  tiny.secondary_spacing_mm = 1e-9;  // used to allocate 21 GB of bins
  EXPECT_THROW(placeCordAttachments(valve_.valve_case.mesh, tiny), std::invalid_argument);
}

TEST(SpacedCordCount, RoundsLengthOverSpacingAndRefusesWhatAnIntCannotHold) {
  EXPECT_EQ(spacedCordCount(81.0, 4.0, "primary"), 20);
  EXPECT_EQ(spacedCordCount(82.0, 4.0, "primary"), 21);  // half away from zero, as lround
  EXPECT_EQ(spacedCordCount(0.0, 4.0, "primary"), 0);
  EXPECT_THROW(spacedCordCount(80.0, 0.05, "primary"), std::invalid_argument);
  EXPECT_THROW(spacedCordCount(80.0, NAN, "primary"), std::invalid_argument);
  EXPECT_THROW(spacedCordCount(1e300, 4.0, "primary"), std::invalid_argument);
  EXPECT_THROW(spacedCordCount(INFINITY, 4.0, "primary"), std::invalid_argument);
  try {
    spacedCordCount(80.0, 1e-9, "secondary cord spacing");
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("secondary cord spacing: must be at least 0.1"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(AutomaticPlacement, SplitsCordsEvenlyBetweenTheTwoTipsOnASymmetricValve) {
  const CordSet set = heuristicCordSet(valve_.valve_case);
  int anterolateral = 0;
  for (const Cord& cord : set.cords) anterolateral += cord.tip == 0;
  EXPECT_NEAR(anterolateral, static_cast<double>(set.cords.size()) / 2.0, 2.0);
  // Paper: tips lie below the leaflet centroids, on the ventricular side.
  EXPECT_GT(set.tips[0].position.y(), 0.0);
  EXPECT_LT(set.tips[1].position.y(), 0.0);
  EXPECT_LT(set.tips[0].position.z(), -10.0);
}

}  // namespace
}  // namespace chordfit
