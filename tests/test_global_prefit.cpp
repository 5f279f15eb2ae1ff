// The global pre-fit (inverse/global_prefit.h): a common factor on the free cords, then one
// factor per cord kind. Noise-free tracings of a closure whose primaries and secondaries are
// scaled differently: the common factor alone cannot reproduce them, the kind stage can.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/closure_model.h"
#include "core/metrics.h"
#include "inverse/global_prefit.h"
#include "tests/test_prefit_start.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

// The truth's factors; the pre-fit's grids (default bounds [0.7, 1.5]: common 0.7, 0.8, ...,
// 1.5 plus refinement, kind stage +-0.05 and +-0.1 around the common factor) need not hit them.
constexpr double kPrimaryScale = 0.8;
constexpr double kSecondaryScale = 0.9;

struct KindProblem {
  ValveCase valve_case;
  SimulationSettings settings;
  CordSet seed;  // the case's heuristic cords, scale 1
};

const KindProblem& kindProblem() {
  static const KindProblem problem = [] {
    KindProblem p;
    testing::BundledCase bundled = testing::bundledCase("small-normal");
    p.valve_case = bundled.valve_case;
    p.settings = bundled.settings;
    p.seed = *p.valve_case.cords;
    for (Cord& cord : p.seed.cords) cord.rest_length = cord.seed_rest_length;
    const CordSet truth = inverse::scaleFreeCords(p.seed, kPrimaryScale, kSecondaryScale);
    p.valve_case.tracings = testing::tracingsOfTruth(p.valve_case, truth, p.settings, 6);
    return p;
  }();
  return problem;
}

// A seed whose cords are not at scale 1 (a fit's cords.json as the seed of another fit): the
// pre-fit's factors keep every scale inside the bounds, so the optimiser's start is not
// clamped back (which threw the pre-fit away); a scale-1 cord is scaled exactly as before,
// and manual and locked cords not at all.
TEST(GlobalPrefit, ScaledCordsStayInsideTheScaleBounds) {
  CordSet seed;
  for (const double scale : {1.0, 0.75, 1.4, 1.0, 1.0}) {
    Cord cord;
    cord.kind = CordKind::kPrimary;
    cord.seed_rest_length = 20.0;
    cord.rest_length = 20.0 * scale;
    seed.cords.push_back(cord);
  }
  seed.cords[3].provenance = Provenance::kManual;
  seed.cords[4].locked = true;
  const inverse::ParameterBounds bounds;  // [0.7, 1.5]
  const CordSet shorter = inverse::scaleFreeCords(seed, 0.8, 0.8, bounds);
  EXPECT_EQ(shorter.cords[0].rest_length, 20.0 * 0.8);
  EXPECT_EQ(shorter.cords[1].rest_length, 20.0 * 0.7) << "0.75 x 0.8 = 0.6, below the bound";
  EXPECT_EQ(shorter.cords[2].rest_length, 28.0 * 0.8);
  EXPECT_EQ(shorter.cords[3].rest_length, 20.0);
  EXPECT_EQ(shorter.cords[4].rest_length, 20.0);
  const CordSet longer = inverse::scaleFreeCords(seed, 1.2, 1.2, bounds);
  EXPECT_EQ(longer.cords[2].rest_length, 20.0 * 1.5) << "1.4 x 1.2 = 1.68, above the bound";
  // Without bounds (the plain overload) the scale-1 cords get the same bits.
  EXPECT_EQ(inverse::scaleFreeCords(seed, 0.8, 0.8).cords[0].rest_length,
            shorter.cords[0].rest_length);
}

// A cord a pre-fit set to seed * 0.7 has scale() = 0.69999999999999984: the start is on the
// bound, not beyond it, and the cords it gives back are the start's, bit for bit.
TEST(FitParameterization, AStartWithinRoundingOfABoundIsNotClamped) {
  const KindProblem& p = kindProblem();
  CordSet start = p.seed;
  for (Cord& cord : start.cords) cord.rest_length = cord.seed_rest_length * 0.7;
  const inverse::ParameterBounds bounds;
  const inverse::FitParameterization parameters(p.valve_case, start,
                                                inverse::ParameterMode::kScales, bounds);
  EXPECT_FALSE(parameters.startClamped());
  for (int k = 0; k < parameters.size(); ++k) {
    EXPECT_GE(parameters.initial()(k), 0.7);
    EXPECT_NEAR(parameters.initial()(k), 0.7, 1e-12);
  }
  const CordSet again = parameters.apply(parameters.initial());
  for (std::size_t c = 0; c < start.cords.size(); ++c)
    EXPECT_EQ(again.cords[c].rest_length, start.cords[c].rest_length) << c;
}

TEST(GlobalPrefit, ScalesEachCordKindOnItsOwn) {
  const KindProblem& p = kindProblem();
  ASSERT_TRUE(std::any_of(p.seed.cords.begin(), p.seed.cords.end(),
                          [](const Cord& c) { return c.kind == CordKind::kSecondary; }));
  const inverse::ParameterBounds bounds;
  const inverse::FitParameterization parameters(p.valve_case, p.seed,
                                                inverse::ParameterMode::kScales, bounds);
  // The whole-mesh residual: this tests the kind stage's mechanism on noise-free data. With
  // the default own-leaflet residual the one round of the stage takes another path on this
  // problem (primaries 0.78, secondaries 0.83, cost 118 against 213 for the best common
  // factor); a second round fixed that but did worse on the cohort (docs/fitting.md,
  // "Own-leaflet residual: pre-fit variants").
  inverse::ResidualOptions whole_mesh;
  whole_mesh.own_leaflet = false;
  const inverse::ForwardResidual residual(p.valve_case, parameters, p.settings, whole_mesh);
  const std::vector<inverse::ForwardEvaluation> seed =
      inverse::closeCordSets(p.valve_case, {p.seed}, residual, 2);
  ASSERT_TRUE(seed[0].ok()) << seed[0].error;

  inverse::PrefitOptions options;
  const inverse::PrefitResult result =
      inverse::globalScalePrefit(p.valve_case, p.seed, seed[0], bounds, residual, options);
  ASSERT_FALSE(result.costs.empty());
  const double best_common = *std::min_element(result.costs.begin(), result.costs.end());
  // The secondaries end relatively longer than the primaries, as in the truth, and the data
  // cost falls well below that of the best common factor.
  EXPECT_GT(result.secondary_factor, result.primary_factor);
  EXPECT_LT(std::abs(result.primary_factor - kPrimaryScale), 0.05);
  // The secondaries are the weakly determined kind here: which grid point wins depends on
  // solver details (0.97 with the late drag, 0.92 without it; with the 10 ms pressure ramp the
  // common factor 0.867 itself, the primaries moving to 0.817).
  EXPECT_LT(std::abs(result.secondary_factor - kSecondaryScale), 0.075);
  // Measured: 31.8 against 251 with the 6 ms ramp, 51.9 against 166 with the 10 ms ramp (51.9
  // against 91.2 with 12 ms).
  EXPECT_LT(result.best.cost, 0.5 * best_common) << "better than any common factor";
  EXPECT_EQ(result.forward_sims, static_cast<int>(result.costs.size()) + 2 * options.kind_points);
  // The start is the seed with the two factors on its free cords.
  for (std::size_t c = 0; c < p.seed.cords.size(); ++c) {
    const Cord& cord = result.start.cords[c];
    const double factor =
        cord.kind == CordKind::kPrimary ? result.primary_factor : result.secondary_factor;
    EXPECT_DOUBLE_EQ(cord.rest_length, p.seed.cords[c].rest_length * factor) << c;
  }

  // Without the kind stage: one factor for both kinds.
  options.kind_points = 0;
  const inverse::PrefitResult common =
      inverse::globalScalePrefit(p.valve_case, p.seed, seed[0], bounds, residual, options);
  EXPECT_EQ(common.primary_factor, common.secondary_factor);
  EXPECT_EQ(common.primary_factor, common.factor);
  EXPECT_EQ(common.forward_sims, static_cast<int>(common.costs.size()));
}

}  // namespace
}  // namespace chordfit
