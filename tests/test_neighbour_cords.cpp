// The regularisation's neighbour pairs (inverse/forward_residual.h, neighbouringCords): cords of
// one group and kind, adjacent along the annulus, also for a group across the angle cut of
// atan2 at +-pi (mid-P2), where sorting by angle alone pairs the group's two ends.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <set>

#include "core/annulus_plane.h"
#include "core/carpentier.h"
#include "core/case_io.h"
#include "inverse/fit_parameters.h"
#include "inverse/forward_residual.h"

namespace chordfit {
namespace {

ValveCase smallNormalCase() {
  Diagnostics diagnostics;
  auto loaded = loadCase(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal", diagnostics);
  if (!loaded || !loaded->cords) throw std::runtime_error("bundled case small-normal missing");
  return *loaded;
}

TEST(NeighbouringCords, AGroupAcrossTheAngleCutIsChainedAlongTheAnnulus) {
  ValveCase valve_case = smallNormalCase();
  CordSet cords = *valve_case.cords;
  const AnnulusFrame frame = openAnnulusFrame(valve_case.mesh);
  // Every primary within 0.9 rad of the cut goes to a tip of its own: one group whose angles
  // are near +pi and near -pi, as when a case's own tips put mid-P2 cords on one tip.
  cords.tips.push_back(cords.tips.front());
  cords.tips.back().name = "mid-P2";
  const int tip = static_cast<int>(cords.tips.size()) - 1;
  std::vector<std::pair<double, int>> moved;  // (angle, cord)
  for (std::size_t c = 0; c < cords.cords.size(); ++c) {
    Cord& cord = cords.cords[c];
    const double angle = annulusAngle(frame, insertionPosition(cord, valve_case.mesh.V));
    if (cord.kind != CordKind::kPrimary || std::abs(angle) < M_PI - 0.9) continue;
    cord.tip = tip;
    cord.locked = false;
    moved.push_back({angle, static_cast<int>(c)});
  }
  std::sort(moved.begin(), moved.end());
  int below_cut = 0;  // cords at negative angles (just past -pi)
  for (const auto& m : moved) below_cut += m.first < 0.0 ? 1 : 0;
  ASSERT_GE(below_cut, 1) << "no cord of the test group on the -pi side";
  ASSERT_GE(static_cast<int>(moved.size()) - below_cut, 1) << "none on the +pi side";

  const inverse::FitParameterization parameters(valve_case, cords, inverse::ParameterMode::kScales,
                                                inverse::ParameterBounds{});
  const auto pairs = inverse::neighbouringCords(valve_case, parameters);
  std::set<std::pair<int, int>> in_group;
  for (auto [a, b] : pairs) {
    if (cords.cords[a].tip == tip || cords.cords[b].tip == tip) {
      // A pair never joins the test group with another group.
      EXPECT_EQ(cords.cords[a].tip, tip);
      EXPECT_EQ(cords.cords[b].tip, tip);
      in_group.insert({std::min(a, b), std::max(a, b)});
    }
  }
  // Along the annulus: from the cord nearest +pi's side start (smallest positive angle ...
  // largest) across the cut to -pi ... the largest negative angle, each to the next.
  std::vector<int> along;
  for (const auto& m : moved)
    if (m.first >= 0.0) along.push_back(m.second);
  for (const auto& m : moved)
    if (m.first < 0.0) along.push_back(m.second);
  std::set<std::pair<int, int>> expected;
  for (std::size_t i = 1; i < along.size(); ++i)
    expected.insert({std::min(along[i - 1], along[i]), std::max(along[i - 1], along[i])});
  EXPECT_EQ(in_group, expected);
  // The two cords beside the cut are neighbours; the group's two ends are not.
  const int before_cut = moved.back().second, after_cut = moved.front().second;
  EXPECT_TRUE(in_group.count({std::min(before_cut, after_cut), std::max(before_cut, after_cut)}));
}

TEST(NeighbouringCords, GroupsAwayFromTheCutKeepTheirAngularOrder) {
  const ValveCase valve_case = smallNormalCase();
  CordSet cords = *valve_case.cords;
  for (Cord& cord : cords.cords) cord.locked = false;
  const inverse::FitParameterization parameters(valve_case, cords, inverse::ParameterMode::kScales,
                                                inverse::ParameterBounds{});
  const AnnulusFrame frame = openAnnulusFrame(valve_case.mesh);
  const auto groups = inverse::cordGroups(valve_case, cords);
  for (auto [a, b] : inverse::neighbouringCords(valve_case, parameters)) {
    EXPECT_EQ(groups[a], groups[b]);
    EXPECT_EQ(cords.cords[a].kind, cords.cords[b].kind);
    // No cord of the same group and kind lies between the two along the annulus.
    const double angle_a =
        annulusAngle(frame, insertionPosition(cords.cords[a], valve_case.mesh.V));
    const double angle_b =
        annulusAngle(frame, insertionPosition(cords.cords[b], valve_case.mesh.V));
    for (std::size_t c = 0; c < cords.cords.size(); ++c) {
      if (static_cast<int>(c) == a || static_cast<int>(c) == b || groups[c] != groups[a] ||
          cords.cords[c].kind != cords.cords[a].kind)
        continue;
      const double angle =
          annulusAngle(frame, insertionPosition(cords.cords[c], valve_case.mesh.V));
      EXPECT_FALSE(angle > std::min(angle_a, angle_b) && angle < std::max(angle_a, angle_b))
          << "cord " << c << " lies between neighbours " << a << " and " << b;
    }
  }
}

}  // namespace
}  // namespace chordfit
