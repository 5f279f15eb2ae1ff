// Simulator behaviour on a small clamped disc under pressure: cords (paper eq. 1),
// determinism, divergence detection and input validation.
#include <cmath>
#include <cstring>
#include <thread>

#include <gtest/gtest.h>

#include "core/cord_insertion.h"
#include "core/simulator.h"
#include "tests/test_sheets.h"

namespace chordfit {
namespace {

constexpr double kDiscRadius = 10.0;  // mm
constexpr int kDiscRings = 10;
constexpr double kCordLengthTolerance = 0.05;  // mm, design requirement for inextensible cords

SimulationSettings discSettings() {
  SimulationSettings settings;  // default leaflet material and 100 mmHg
  settings.contact = false;     // a flat disc cannot touch itself
  return settings;
}

bool bitIdentical(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// Where the cord at the centre vertex inserts in `V`: the weighted mean of its insertion patch
// (cord_insertion.h), the vertex itself when the radius is 0.
Eigen::Vector3d centreInsertion(const SimulationModel& model, const SimulationSettings& settings,
                                const Eigen::MatrixXd& V) {
  return insertionPosition(
      cordInsertionWeights(model.V_rest, model.F, {0}, {1.0}, settings.cord_insertion_radius_mm),
      V);
}

TEST(SimulatorCords, StretchedInextensibleCordHoldsItsInsertionAtRestLengthUnderFullPressure) {
  // Without the cord the centre bulges ~1.6 mm toward +z; the cord from the tip 10 mm below
  // allows 0.5 mm. At a point (radius 0, the default) the cord holds its vertex; spread over
  // 2 mm it holds the weighted mean of its patch (the vertex under the cord, where the pull is
  // densest, then sits lower than the mean).
  for (double radius : {0.0, 2.0}) {
    SimulationModel model = testing::clampedDiscModel(kDiscRadius, kDiscRings);
    model.cords.push_back({0, 0, 10.5, 0.0, std::nullopt});
    SimulationSettings settings = discSettings();
    settings.cord_insertion_radius_mm = radius;
    const SimulationResult result = simulate(model, settings);
    ASSERT_TRUE(result.ok()) << result.error;
    EXPECT_TRUE(result.converged);
    const Eigen::Vector3d tip = model.tip_end.row(0).transpose();
    EXPECT_NEAR((centreInsertion(model, settings, result.V) - tip).norm(), 10.5,
                kCordLengthTolerance)
        << "radius " << radius;
    EXPECT_GT(result.cord_force(0), 0.0);  // taut
  }
}

TEST(SimulatorCords, ElasticCordStretchesByForceTimesCompliance) {
  SimulationModel model = testing::clampedDiscModel(kDiscRadius, kDiscRings);
  constexpr double kCompliance = 0.5;  // mm/N
  model.cords.push_back({0, 0, 10.5, kCompliance, std::nullopt});
  SimulationSettings settings = discSettings();
  settings.tolerance_mm = 1e-6;
  const SimulationResult result = simulate(model, settings);
  ASSERT_TRUE(result.ok()) << result.error;
  const double stretch =
      (centreInsertion(model, settings, result.V) - model.tip_end.row(0).transpose()).norm() - 10.5;
  EXPECT_GT(stretch, 0.0);
  EXPECT_NEAR(stretch, kCompliance * result.cord_force(0), 1e-3);
}

TEST(SimulatorCords, SlackCordExertsNoForceAndChangesNothing) {
  const SimulationModel without = testing::clampedDiscModel(kDiscRadius, kDiscRings);
  SimulationModel with = without;
  with.cords.push_back(
      {0, 0, 20.0, 0.0, std::nullopt});  // longer than the centre ever gets from the tip
  const SimulationResult a = simulate(without, discSettings());
  const SimulationResult b = simulate(with, discSettings());
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(b.cord_force(0), 0.0);
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_TRUE(bitIdentical(a.V, b.V));
}

TEST(SimulatorDeterminism, TwoRunsAreBitIdenticalAlsoWhenRunConcurrently) {
  SimulationModel model = testing::clampedDiscModel(kDiscRadius, kDiscRings);
  model.cords.push_back({0, 0, 10.5, 0.0, std::nullopt});
  const SimulationResult first = simulate(model, discSettings());
  SimulationResult second, third;
  std::thread t1([&] { second = simulate(model, discSettings()); });
  std::thread t2([&] { third = simulate(model, discSettings()); });
  t1.join();
  t2.join();
  ASSERT_TRUE(first.ok() && second.ok() && third.ok());
  EXPECT_TRUE(bitIdentical(first.V, second.V));
  EXPECT_TRUE(bitIdentical(first.V, third.V));
  EXPECT_EQ(first.steps, second.steps);
}

TEST(SimulatorDivergence, ExplodingPositionsAreReportedAsAnError) {
  // Valid input cannot be made to diverge quickly, so the guard is tested with a PM tip that
  // runs 1e6 mm away during the ramp: its taut cord drags the centre vertex ~1 m per step,
  // which the step loop must report as an error, returning no positions.
  SimulationModel model = testing::clampedDiscModel(kDiscRadius, kDiscRings);
  model.tip_end = Eigen::RowVector3d(0.0, 0.0, -1e6);
  model.cords.push_back({0, 0, 10.0, 0.0, std::nullopt});  // tip 0 to the centre vertex
  const SimulationResult result = simulate(model, discSettings());
  EXPECT_FALSE(result.ok());
  EXPECT_TRUE(result.diverged);
  EXPECT_NE(result.error.find("diverged"), std::string::npos) << result.error;
  EXPECT_LE(result.steps, 3) << "noticed at once";
  EXPECT_EQ(result.V.size(), 0);
}

TEST(SimulatorValidation, RejectsATimeStepTooSmallToUse) {
  // dt = 1e-200 ms overflowed 1 / dt^2 and diverged (exit 3) before it was range-checked.
  SimulationSettings settings = discSettings();
  settings.dt_ms = 1e-200;
  SimulationResult result = simulate(testing::clampedDiscModel(kDiscRadius, kDiscRings), settings);
  EXPECT_FALSE(result.ok());
  EXPECT_FALSE(result.diverged);
  EXPECT_NE(result.error.find("dt_ms"), std::string::npos) << result.error;
  // A usable step whose pressure ramp alone outlasts the step cap cannot settle either.
  settings.dt_ms = 1e-3;  // the 10 ms ramp: 10,000 steps
  settings.max_steps = 5000;
  result = simulate(testing::clampedDiscModel(kDiscRadius, kDiscRings), settings);
  EXPECT_FALSE(result.ok());
  EXPECT_NE(result.error.find("max_steps"), std::string::npos) << result.error;
  settings.max_steps = 10001;
  EXPECT_TRUE(settingsProblems(settings).empty());
}

TEST(SimulatorDivergence, HugeTimeStepIsRejected) {
  SimulationSettings settings = discSettings();
  settings.dt_ms = 1e160;  // dt^2 overflows
  const SimulationResult result =
      simulate(testing::clampedDiscModel(kDiscRadius, kDiscRings), settings);
  EXPECT_FALSE(result.ok());
  EXPECT_EQ(result.V.size(), 0);
}

TEST(SimulatorValidation, RejectsNonFiniteStartAndBadSettings) {
  const SimulationModel model = testing::clampedDiscModel(kDiscRadius, kDiscRings);
  Eigen::MatrixXd start = model.V_rest;
  start(3, 1) = std::nan("");
  EXPECT_FALSE(simulate(model, discSettings(), &start).ok());
  SimulationSettings settings = discSettings();
  settings.iterations = 0;
  EXPECT_FALSE(simulate(model, settings).ok());
  settings = discSettings();
  settings.dt_ms = -1.0;
  EXPECT_FALSE(simulate(model, settings).ok());
  SimulationModel bad = model;
  bad.cords.push_back({3, 0, 10.0, 0.0, std::nullopt});  // no tip 3
  EXPECT_FALSE(simulate(bad, discSettings()).ok());
}

// Regional tissue (SimulationModel::tissue_stiffness): a uniform factor k is the material with
// E k (same compliances up to rounding, so the same equilibrium); a softer half bulges more.
TEST(SimulatorTissue, UniformFactorEqualsScaledModulusAndASofterHalfBulgesMore) {
  SimulationModel regional = testing::clampedDiscModel(kDiscRadius, kDiscRings);
  regional.tissue_stiffness = Eigen::VectorXd::Constant(regional.V_rest.rows(), 0.5);
  SimulationSettings settings = discSettings();
  settings.tolerance_mm = 1e-6;
  const SimulationResult half = simulate(regional, settings);
  SimulationSettings softer = settings;
  softer.material.youngs_modulus_mpa *= 0.5;
  const SimulationResult reference =
      simulate(testing::clampedDiscModel(kDiscRadius, kDiscRings), softer);
  ASSERT_TRUE(half.ok() && reference.ok()) << half.error << reference.error;
  EXPECT_NEAR(half.V(0, 2), reference.V(0, 2), 1e-6 * std::abs(reference.V(0, 2)));

  // Soft (factor 0.2) where x > 0: the deflection at x = +a/2 exceeds the one at x = -a/2.
  for (Eigen::Index v = 0; v < regional.V_rest.rows(); ++v)
    regional.tissue_stiffness(v) = regional.V_rest(v, 0) > 0.0 ? 0.2 : 1.0;
  const SimulationResult soft_half = simulate(regional, settings);
  ASSERT_TRUE(soft_half.ok()) << soft_half.error;
  const int mid = kDiscRings / 2;
  const int plus = testing::discRingStart(mid);  // angle 0: x = +a/2
  const int minus = plus + 3 * mid;              // angle pi: x = -a/2
  ASSERT_NEAR(regional.V_rest(minus, 0), -0.5 * kDiscRadius, 1e-9);
  EXPECT_GT(soft_half.V(plus, 2), 1.2 * soft_half.V(minus, 2));
}

TEST(SimulatorTissue, RejectsAWrongCountOrANonPositiveFactor) {
  SimulationModel model = testing::clampedDiscModel(kDiscRadius, kDiscRings);
  model.tissue_stiffness = Eigen::VectorXd::Ones(3);
  SimulationResult result = simulate(model, discSettings());
  EXPECT_NE(result.error.find("one factor per vertex"), std::string::npos) << result.error;
  model.tissue_stiffness = Eigen::VectorXd::Ones(model.V_rest.rows());
  model.tissue_stiffness(7) = 0.0;
  result = simulate(model, discSettings());
  EXPECT_NE(result.error.find("positive and finite"), std::string::npos) << result.error;
}

TEST(SimulatorSettings, JsonOverridesKnownKeysAndReportsUnknownOnes) {
  Diagnostics diagnostics;
  const SimulationSettings s = settingsFromJson(
      R"({"pressure_mmhg": 80, "youngs_modulus_mpa": 2.5, "iterations": 3, "phase": "open",
          "contact": false, "bogus": 1})",
      diagnostics);
  EXPECT_EQ(s.pressure_mmhg, 80.0);
  EXPECT_EQ(s.material.youngs_modulus_mpa, 2.5);
  EXPECT_EQ(s.iterations, 3);
  EXPECT_EQ(s.phase, ClosurePhase::kOpen);
  EXPECT_FALSE(s.contact);
  ASSERT_EQ(diagnostics.problems().size(), 1u);
  EXPECT_EQ(diagnostics.problems()[0].where, "simulation.bogus");
}

TEST(SimulatorProgress, CallbackIsCalledEveryNStepsAndAtTheEnd) {
  SimulationSettings settings = discSettings();
  settings.progress_every = 50;
  int calls = 0, last_step = 0;
  settings.progress = [&](const SimulationProgress& p) {
    ++calls;
    last_step = p.step;
  };
  const SimulationResult result =
      simulate(testing::clampedDiscModel(kDiscRadius, kDiscRings), settings);
  ASSERT_TRUE(result.ok());
  EXPECT_EQ(calls, result.steps / 50 + 1);
  EXPECT_EQ(last_step, result.steps);
}

}  // namespace
}  // namespace chordfit
