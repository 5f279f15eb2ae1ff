// The pressure ramp (SimulationSettings::ramp_ms) decides which equilibrium a cold closure of a
// prolapsing flap ends in. The bundled prolapse-P2 case (seed 3, case edge 2.5 mm) closed with
// its TRUE rest lengths and PM tips: with the 6 ms ramp of the simulator before 2026-11-25 the
// flap overshoots and closes flat (no prolapse anywhere; the benchmark's "true cords on the
// case mesh" row, 0.96 mm from the tracings), with the default 10 ms ramp it takes the truth's
// branch and prolapses in P2, as the truth does (docs/performance.md, "Pressure ramp").
#include <gtest/gtest.h>

#include <filesystem>

#include "core/closure_model.h"
#include "core/cordset_io.h"
#include "core/metrics.h"
#include "core/synthetic_case.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;

TEST(PressureRamp, SlowRampLetsTheTrueCordsMakeTheFlapOnTheCaseMesh) {
  const testing::BundledCase bundled = testing::bundledCase("prolapse-P2");
  Diagnostics diagnostics;
  CordSet true_set;
  ASSERT_TRUE(readCordSet(fs::path(CHORDFIT_CASES_DIR) / "prolapse-P2" / "truth" / "cords.json",
                          "truth/cords.json", true_set, diagnostics));
  const CordSet truth_cords = trueCordsOnCaseMesh(*bundled.valve_case.cords, true_set);
  ASSERT_EQ(bundled.settings.ramp_ms, SimulationSettings{}.ramp_ms) << "the case sets no ramp";

  SimulationSettings fast = bundled.settings;
  fast.ramp_ms = 6.0;
  const SimulationResult fast_closed = simulateClosure(bundled.valve_case, truth_cords, fast);
  const SimulationResult slow_closed =
      simulateClosure(bundled.valve_case, truth_cords, bundled.settings);
  ASSERT_TRUE(fast_closed.ok()) << fast_closed.error;
  ASSERT_TRUE(slow_closed.ok()) << slow_closed.error;
  EXPECT_TRUE(fast_closed.converged);
  EXPECT_TRUE(slow_closed.converged);

  const ProlapseResult fast_prolapse = prolapseOfMesh(bundled.valve_case, fast_closed.V);
  const ProlapseResult slow_prolapse = prolapseOfMesh(bundled.valve_case, slow_closed.V);
  EXPECT_TRUE(fast_prolapse.segments.empty()) << "the 6 ms closure's flap";
  EXPECT_EQ(slow_prolapse.segments, std::vector<std::string>{"P2"});
  // And it explains the tracings better: mean deviation 0.96 -> 0.59 mm (noise floor 0.22).
  const double fast_mean = computeMetrics(bundled.valve_case, fast_closed.V).deviation.mean;
  const double slow_mean = computeMetrics(bundled.valve_case, slow_closed.V).deviation.mean;
  EXPECT_LT(slow_mean, 0.75 * fast_mean);
}

}  // namespace
}  // namespace chordfit
