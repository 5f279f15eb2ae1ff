// The segment pre-fit (inverse/segment_prefit.h): from a uniform cord set it finds a segment
// whose cords are longer in the truth (a prolapse a gradient cannot reach), and it leaves
// manual and locked cords alone.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/closure_model.h"
#include "core/cohort_presets.h"
#include "core/metrics.h"
#include "inverse/global_prefit.h"
#include "inverse/segment_prefit.h"
#include "tests/test_prefit_start.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

constexpr double kBaseScale = 0.8;    // every cord taut, as the cohort's normal cords
constexpr double kP2Scale = 1.3;      // on the pre-fit's default grid (0.7, 0.9, ..., 1.5)
constexpr double kP2SlackFrom = 1.1;  // grid point from which the P2 cords are slack (measured)

using SegmentProblem = testing::PrefitStart;  // base: all cords at kBaseScale

// The bundled small case with noise-free tracings of a closure whose P2 cords are at kP2Scale;
// cord 0 of P2 is a locked manual cord (at the base scale in truth and start), and the first
// cord outside P2 an unlocked manual one.
const SegmentProblem& segmentProblem() {
  static const SegmentProblem problem = [] {
    SegmentProblem p = testing::smallNormalPrefitStart(kBaseScale);
    CordSet truth = p.base;
    bool locked_one = false, manual_one = false;
    for (std::size_t c = 0; c < truth.cords.size(); ++c) {
      const bool in_p2 = p.vertex_segment(p.base.cords[c].vertex) == p.p2;
      if (in_p2 && !locked_one) {
        locked_one = true;
        for (CordSet* set : {&p.base, &truth}) {
          set->cords[c].locked = true;
          set->cords[c].provenance = Provenance::kManual;
        }
      } else if (in_p2) {
        truth.cords[c].rest_length = truth.cords[c].seed_rest_length * kP2Scale;
      } else if (!manual_one) {
        manual_one = true;
        p.base.cords[c].provenance = Provenance::kManual;
      }
    }
    if (!locked_one) throw std::runtime_error("small-normal has no P2 cord");
    p.valve_case.tracings = testing::tracingsOfTruth(p.valve_case, truth, p.settings, 3);
    return p;
  }();
  return problem;
}

TEST(SegmentPrefit, FindsTheLongerP2CordsAndKeepsManualCords) {
  const SegmentProblem& p = segmentProblem();
  inverse::ParameterBounds bounds;  // [0.7, 1.5]: grid 0.7, 0.9, 1.1, 1.3, 1.5
  const inverse::FitParameterization parameters(p.valve_case, p.base,
                                                inverse::ParameterMode::kScales, bounds);
  // The whole-mesh residual: this tests the pass's mechanism on noise-free data. With the
  // default own-leaflet residual the pass takes "A2 0.7" before it reaches "P2 1.1" on this
  // problem and ends at a cost of 78 instead of 0; a second look or a best-first order fixed
  // that but did worse on the cohort (docs/fitting.md, "Own-leaflet residual: pre-fit
  // variants").
  inverse::ResidualOptions whole_mesh;
  whole_mesh.own_leaflet = false;
  const inverse::ForwardResidual residual(p.valve_case, parameters, p.settings, whole_mesh);
  const std::vector<inverse::ForwardEvaluation> start =
      inverse::closeCordSets(p.valve_case, {p.base}, residual, 2);
  ASSERT_TRUE(start[0].ok()) << start[0].error;

  const inverse::SegmentPrefitResult result =
      inverse::segmentScalePrefit(p.valve_case, p.base, start[0], bounds, residual, {});
  // Noise-free tracings: the truth's closure is reproduced exactly. On this normal anatomy
  // the P2 cords go slack above 1.1 (1.1, 1.3 and 1.5 close to the same bytes), and the
  // first of equal costs wins, so the pre-fit ends at the shortest scale that fits.
  EXPECT_LT(result.best.cost, 1e-9 * start[0].cost);
  EXPECT_GT(result.forward_sims, 0);
  int p2_free = 0;
  for (std::size_t c = 0; c < p.base.cords.size(); ++c) {
    const Cord& before = p.base.cords[c];
    const Cord& after = result.start.cords[c];
    if (before.locked || before.provenance == Provenance::kManual) {
      EXPECT_EQ(after.rest_length, before.rest_length) << "manual cord " << c;
      EXPECT_EQ(after.locked, before.locked);
    } else if (p.vertex_segment(before.vertex) == p.p2) {
      ++p2_free;
      EXPECT_NEAR(after.scale(), kP2SlackFrom, 1e-9) << "P2 cord " << c;
    }
  }
  EXPECT_GT(p2_free, 0);
  bool reported = false;
  for (const std::string& change : result.changed) reported |= change.rfind("P2 1.1", 0) == 0;
  EXPECT_TRUE(reported) << "changes reported: " << result.changed.size();
}

TEST(SegmentPrefit, DisabledChangesNothing) {
  const SegmentProblem& p = segmentProblem();
  inverse::ForwardEvaluation start;
  start.cost = 1.0;
  inverse::SegmentPrefitOptions options;
  options.enabled = false;
  const inverse::FitParameterization parameters(p.valve_case, p.base,
                                                inverse::ParameterMode::kScales, {});
  const inverse::ForwardResidual residual(p.valve_case, parameters, p.settings, {});
  const inverse::SegmentPrefitResult result =
      inverse::segmentScalePrefit(p.valve_case, p.base, start, {}, residual, options);
  EXPECT_EQ(result.forward_sims, 0);
  EXPECT_TRUE(result.changed.empty());
  for (std::size_t c = 0; c < p.base.cords.size(); ++c) {
    EXPECT_EQ(result.start.cords[c].rest_length, p.base.cords[c].rest_length);
  }
}

}  // namespace
}  // namespace chordfit
