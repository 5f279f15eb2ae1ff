// Closures that reach their step cap without settling (simulator.h: max_warm_steps,
// average_unsettled_steps). The result of such a closure is the mean of its last steps'
// positions; a run capped at step k returns exactly the state after step k, so the mean can
// be checked against runs capped at each of the averaged steps.
#include <gtest/gtest.h>

#include "core/closure_model.h"
#include "tests/test_coarse_valve.h"

namespace chordfit {
namespace {

using testing::CoarseValve;

// A cap halfway between the end of the ramp and the settled closure: still moving there.
int unsettledCap(const CoarseValve& valve) {
  const SimulationResult full = valve.close(SimulationSettings{});
  EXPECT_TRUE(full.ok() && full.converged) << full.error;
  const int ramp_steps = static_cast<int>(SimulationSettings{}.ramp_ms / full.dt_ms) + 1;
  EXPECT_GT(full.steps, ramp_steps + 40);
  return (ramp_steps + full.steps) / 2;
}

TEST(UnsettledClosure, ResultIsTheMeanOfTheLastStepsStates) {
  const CoarseValve valve;
  const int cap = unsettledCap(valve);
  constexpr int kAveraged = 5;
  SimulationSettings settings;
  settings.max_steps = cap;
  settings.average_unsettled_steps = kAveraged;
  const SimulationResult averaged = valve.close(settings);
  ASSERT_TRUE(averaged.ok()) << averaged.error;
  EXPECT_FALSE(averaged.converged);
  EXPECT_EQ(averaged.steps, cap);
  EXPECT_EQ(averaged.averaged_steps, kAveraged);

  // The states after steps cap-4 .. cap, each from a run capped there, without averaging.
  settings.average_unsettled_steps = 0;
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(averaged.V.rows(), 3);
  SimulationResult last;
  for (int k = cap - kAveraged + 1; k <= cap; ++k) {
    settings.max_steps = k;
    last = valve.close(settings);
    ASSERT_TRUE(last.ok()) << last.error;
    EXPECT_EQ(last.averaged_steps, 0);
    sum += last.V;
  }
  const Eigen::MatrixXd mean = sum / kAveraged;
  EXPECT_LT((averaged.V - mean).cwiseAbs().maxCoeff(), 1e-12);
  // Still moving: the mean is not the last state.
  EXPECT_GT((averaged.V - last.V).rowwise().norm().maxCoeff(), 1e-6);
  // Dirichlet vertices (the annulus) keep their exact final positions.
  for (int i : valve.valve.valve_case.mesh.annulus)
    EXPECT_TRUE(averaged.V.row(i) == last.V.row(i)) << "annulus vertex " << i;
}

TEST(UnsettledClosure, OnlyStepsAfterTheRampAreAveraged) {
  const CoarseValve valve;
  SimulationSettings settings;
  const SimulationResult probe = valve.close(settings);
  ASSERT_TRUE(probe.ok()) << probe.error;
  const int ramp_steps = static_cast<int>(settings.ramp_ms / probe.dt_ms) + 1;
  settings.max_steps = ramp_steps + 3;
  settings.average_unsettled_steps = 1000;
  const SimulationResult r = valve.close(settings);
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_FALSE(r.converged);
  EXPECT_GE(r.averaged_steps, 3);
  EXPECT_LE(r.averaged_steps, 4);
}

TEST(UnsettledClosure, SettledClosureIsNotAveraged) {
  const CoarseValve valve;
  SimulationSettings settings;
  const SimulationResult with = valve.close(settings);
  settings.average_unsettled_steps = 0;
  const SimulationResult without = valve.close(settings);
  ASSERT_TRUE(with.ok() && without.ok());
  EXPECT_TRUE(with.converged);
  EXPECT_EQ(with.averaged_steps, 0);
  EXPECT_TRUE(with.V == without.V);
}

TEST(UnsettledClosure, WarmStartedClosureStopsAtItsOwnCapButOpeningDoesNot) {
  const CoarseValve valve;
  const int cap = unsettledCap(valve);
  SimulationSettings settings;
  settings.max_steps = cap;
  const SimulationResult moving = valve.close(settings);  // a start state far from rest
  ASSERT_TRUE(moving.ok()) << moving.error;

  settings = SimulationSettings{};
  settings.max_warm_steps = 25;
  const SimulationResult warm = valve.close(settings, &moving.V);
  ASSERT_TRUE(warm.ok()) << warm.error;
  EXPECT_LE(warm.steps, 25);

  const SimulationResult closed = valve.close(SimulationSettings{});
  ASSERT_TRUE(closed.ok() && closed.converged);
  settings.phase = ClosurePhase::kOpen;
  const SimulationResult opened = valve.close(settings, &closed.V);
  ASSERT_TRUE(opened.ok()) << opened.error;
  EXPECT_GT(opened.steps, 25);  // opening is a full run from the closed state, not a warm start
}

TEST(UnsettledClosure, SettingsAreReadFromJsonAndRangeChecked) {
  Diagnostics diagnostics;
  const SimulationSettings s =
      settingsFromJson(R"({"max_warm_steps": 300, "average_unsettled_steps": 0})", diagnostics);
  EXPECT_TRUE(diagnostics.problems().empty());
  EXPECT_EQ(s.max_warm_steps, 300);
  EXPECT_EQ(s.average_unsettled_steps, 0);

  Diagnostics bad;
  settingsFromJson(R"({"max_warm_steps": 0, "average_unsettled_steps": -1})", bad, {},
                   "cases/x/case.json");
  ASSERT_EQ(bad.problems().size(), 2u);
  EXPECT_EQ(bad.problems()[0].file, "cases/x/case.json");
  for (const Problem& p : bad.problems())
    EXPECT_NE(p.what.find("out of range"), std::string::npos) << p.where << ": " << p.what;
}

}  // namespace
}  // namespace chordfit
