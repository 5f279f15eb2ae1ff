// The slack release (inverse/slack_release.h): which cords it raises and to what (a pure
// function of the fitted cords and their closed spans), and what fitCords does with it.
#include <gtest/gtest.h>

#include <vector>

#include "core/cord_insertion.h"
#include "core/heuristic.h"
#include "inverse/fit_cords.h"
#include "inverse/slack_release.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

using inverse::proposeSlackRelease;
using inverse::SlackReleaseProposal;

constexpr double kSeedLength = 20.0;         // mm, every cord's seed (heuristic) rest length
constexpr double kUpper = 1.5;               // the fit's upper scale bound
constexpr int kNormal = 0, kProlapsing = 4;  // segment ids (A1, P2)

struct Fixture {
  CordSet fitted, seed;
  Eigen::VectorXd spans;
  std::vector<int> segments;

  // A cord at `scale` of the seed length; taut (span = rest length) or slack by 3 mm.
  void add(CordKind kind, double scale, bool taut, int segment = kNormal) {
    Cord cord;
    cord.kind = kind;
    cord.seed_rest_length = kSeedLength;
    cord.rest_length = kSeedLength * scale;
    fitted.cords.push_back(cord);
    seed.cords.push_back(cord);
    spans.conservativeResize(spans.size() + 1);
    spans(spans.size() - 1) = taut ? cord.rest_length : cord.rest_length - 3.0;
    segments.push_back(segment);
  }
  SlackReleaseProposal propose(const std::vector<int>& excluded = {}) const {
    return proposeSlackRelease(fitted, seed, spans, segments, excluded, kUpper);
  }
};

TEST(SlackRelease, RaisesSlackCordsBelowTheMedianOfTheTautCordsOfTheirKind) {
  Fixture f;
  f.add(CordKind::kPrimary, 0.76, true);     // 0
  f.add(CordKind::kPrimary, 0.80, true);     // 1
  f.add(CordKind::kPrimary, 0.84, true);     // 2: the primaries' median is 0.80
  f.add(CordKind::kPrimary, 0.70, false);    // 3: slack at the bound -> 0.80
  f.add(CordKind::kPrimary, 0.90, false);    // 4: slack above the median: kept
  f.add(CordKind::kSecondary, 0.70, true);   // 5
  f.add(CordKind::kSecondary, 0.74, true);   // 6: the secondaries' median is 0.72
  f.add(CordKind::kSecondary, 0.71, false);  // 7: slack -> 0.72
  const SlackReleaseProposal p = f.propose();
  EXPECT_NEAR(p.primary_reference, 0.80, 1e-12);
  EXPECT_NEAR(p.secondary_reference, 0.72, 1e-12);
  EXPECT_EQ(p.cords, (std::vector<int>{3, 7}));
  ASSERT_EQ(p.scales.size(), 2u);
  EXPECT_NEAR(p.scales[0], 0.80, 1e-12);
  EXPECT_NEAR(p.scales[1], 0.72, 1e-12);
}

// A slack cord within rounding of its kind's typical scale is at it: it was "raised" from
// 0.6999999999999998 to 0.7, a closure spent on nothing.
TEST(SlackRelease, ACordWithinRoundingOfTheTypicalScaleIsNotRaised) {
  Fixture f;
  f.add(CordKind::kPrimary, 0.70, true);
  f.add(CordKind::kPrimary, 0.70, true);
  f.add(CordKind::kPrimary, 0.6999999999999998, false);
  f.add(CordKind::kPrimary, 0.699, false);
  const SlackReleaseProposal p = f.propose();
  EXPECT_EQ(p.cords, std::vector<int>{3});
}

TEST(SlackRelease, TheRescaledSegmentsCordsDoNotSetTheTypicalScale) {
  Fixture f;
  f.add(CordKind::kPrimary, 0.78, true);
  f.add(CordKind::kPrimary, 1.30, true, kProlapsing);
  f.add(CordKind::kPrimary, 1.30, true, kProlapsing);
  f.add(CordKind::kPrimary, 0.70, false);
  EXPECT_NEAR(f.propose().primary_reference, 1.30, 1e-12);  // dragged up by the prolapse
  const SlackReleaseProposal p = f.propose({kProlapsing});
  EXPECT_NEAR(p.primary_reference, 0.78, 1e-12);
  EXPECT_EQ(p.cords, std::vector<int>{3});
}

TEST(SlackRelease, LeavesManualAndLockedCordsAlone) {
  Fixture f;
  f.add(CordKind::kPrimary, 0.80, true);
  f.add(CordKind::kPrimary, 0.70, false);
  f.add(CordKind::kPrimary, 0.70, false);
  f.add(CordKind::kPrimary, 0.70, false);
  f.seed.cords[1].provenance = Provenance::kManual;  // the user's edit: the fit's prior
  f.seed.cords[2].locked = true;
  EXPECT_EQ(f.propose().cords, std::vector<int>{3});
}

TEST(SlackRelease, NothingWithoutATautCordOfTheKindAndNeverAboveTheBound) {
  Fixture f;
  f.add(CordKind::kSecondary, 0.70, false);
  f.add(CordKind::kPrimary, 1.60, true);  // above the bound (a manual start, say)
  f.add(CordKind::kPrimary, 0.70, false);
  const SlackReleaseProposal p = f.propose();
  EXPECT_EQ(p.secondary_reference, 0.0);
  EXPECT_EQ(p.cords, std::vector<int>{2});
  ASSERT_EQ(p.scales.size(), 1u);
  EXPECT_EQ(p.scales[0], kUpper);
}

TEST(SlackRelease, MismatchedSizesProposeNothing) {
  Fixture f;
  f.add(CordKind::kPrimary, 0.80, true);
  f.add(CordKind::kPrimary, 0.70, false);
  f.segments.pop_back();
  EXPECT_TRUE(f.propose().empty());
}

// A short per-cord fit of the bundled prolapse case from the heuristic (the quick start's, with
// a smaller budget; ~3 s): the raised cords are still slack in the reported closure, which
// fits the tracings as well as the optimiser's best, and the fit stays within its budget.
TEST(SlackReleaseFit, RaisedCordsStaySlackAndTheClosureFitsAsWell) {
  const testing::BundledCase bundled = testing::bundledCase("prolapse-P2");
  const CordSet seed = heuristicCordSet(bundled.valve_case);
  inverse::FitOptions options;
  options.max_sims = 60;
  const inverse::FitOutcome fit =
      inverse::fitCords(bundled.valve_case, seed, bundled.settings, options);
  ASSERT_TRUE(fit.ok()) << fit.error;
  EXPECT_LE(fit.forward_sims, options.max_sims);
  const inverse::SlackReleaseProposal& p = fit.slack_release.proposal;
  ASSERT_FALSE(p.empty()) << "this fit leaves slack cords below their kind's typical scale";
  ASSERT_TRUE(fit.slack_release.kept) << "data cost " << fit.slack_release.optimiser_data_cost
                                      << " -> " << fit.slack_release.data_cost;
  EXPECT_LE(fit.slack_release.data_cost,
            fit.slack_release.optimiser_data_cost * (1.0 + options.slack_release.cost_tolerance));
  for (std::size_t i = 0; i < p.cords.size(); ++i) {
    const Cord& cord = fit.fitted.cords[p.cords[i]];
    EXPECT_DOUBLE_EQ(cord.scale(), p.scales[i]) << "cord " << p.cords[i];
    EXPECT_LT(fit.closed_spans(p.cords[i]), cord.rest_length - kSlackMarginMm)
        << "cord " << p.cords[i] << " pulls after its release";
  }

  options.slack_release.enabled = false;
  const inverse::FitOutcome kept =
      inverse::fitCords(bundled.valve_case, seed, bundled.settings, options);
  ASSERT_TRUE(kept.ok()) << kept.error;
  EXPECT_TRUE(kept.slack_release.proposal.empty());
  EXPECT_FALSE(kept.slack_release.kept);
}

}  // namespace
}  // namespace chordfit
