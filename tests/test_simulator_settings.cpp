// Range checks of the simulation settings (settingsProblems / settingsFromJson): nonsense
// such as a 1e300 mmHg pressure or a NaN tolerance is an input error, never a run.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include <map>

#include "core/simulator.h"

namespace chordfit {
namespace {

bool hasProblem(const std::vector<SettingsProblem>& problems, const std::string& key) {
  for (const SettingsProblem& p : problems)
    if (p.key == key) return true;
  return false;
}

TEST(SimulatorSettingsRanges, DefaultsAreAccepted) {
  EXPECT_TRUE(settingsProblems(SimulationSettings{}).empty());
}

TEST(SimulatorSettingsRanges, NonFiniteValuesAreReportedByKey) {
  SimulationSettings s;
  s.pressure_mmhg = std::numeric_limits<double>::infinity();
  s.tolerance_mm = std::nan("");
  s.material.youngs_modulus_mpa = -std::numeric_limits<double>::infinity();
  const auto problems = settingsProblems(s);
  EXPECT_EQ(problems.size(), 3u);
  EXPECT_TRUE(hasProblem(problems, "pressure_mmhg"));
  EXPECT_TRUE(hasProblem(problems, "tolerance_mm"));
  EXPECT_TRUE(hasProblem(problems, "youngs_modulus_mpa"));
  for (const SettingsProblem& p : problems) EXPECT_NE(p.what.find("finite"), std::string::npos);
}

TEST(SimulatorSettingsRanges, ZeroNegativeAndAbsurdValuesAreRejected) {
  SimulationSettings s;
  s.pressure_mmhg = 1e300;
  s.material.thickness_mm = 0.0;
  s.material.poisson_ratio = 0.5;
  s.drag_time_ms = -1.0;
  s.iterations = 0;
  s.max_steps = 0;
  s.area_floor_fraction = 1.0;  // a floor at the rest area would forbid any compression
  const auto problems = settingsProblems(s);
  for (const char* key : {"pressure_mmhg", "thickness_mm", "poisson_ratio", "drag_time_ms",
                          "iterations", "max_steps", "area_floor_fraction"})
    EXPECT_TRUE(hasProblem(problems, key)) << key;
  EXPECT_EQ(problems.size(), 7u);
}

// A velocity clamp at the settling tolerance would let an open valve pass for settled
// (max_step_mm 5e-5 gave "converged" after 159 steps, 39 % of the orifice open): the clamp
// must be at least 10 x the tolerance; 0 (automatic) and the tolerance's own range stay.
TEST(SimulatorSettingsRanges, AVelocityClampNearTheToleranceIsRefused) {
  SimulationSettings s;
  s.max_step_mm = 5e-5;
  auto problems = settingsProblems(s);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].key, "max_step_mm");
  EXPECT_NE(problems[0].what.find("5e-05 mm is below 10 x tolerance_mm (0.0001 mm)"),
            std::string::npos)
      << problems[0].what;
  s.max_step_mm = 2e-3;  // 20 x
  EXPECT_TRUE(settingsProblems(s).empty());
  s.tolerance_mm = 1e-3;  // the same clamp against a looser tolerance
  EXPECT_TRUE(hasProblem(settingsProblems(s), "max_step_mm"));
  s.max_step_mm = 0.0;
  EXPECT_TRUE(settingsProblems(s).empty());
  // The automatic clamp (0.25 x the contact thickness, 0.25 mm here) against a tolerance
  // above a tenth of it: named at the tolerance.
  s.tolerance_mm = 0.03;
  problems = settingsProblems(s);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].key, "tolerance_mm");
  EXPECT_NE(problems[0].what.find("0.03 mm is more than a tenth of the largest step a vertex may "
                                  "take (0.25 mm, 0.25 x the contact thickness)"),
            std::string::npos)
      << problems[0].what;
  s.material.thickness_mm = 2.0;  // a 0.5 mm clamp
  EXPECT_TRUE(settingsProblems(s).empty());
}

// As for every other object's keys: a typo is named with the setting it may have meant.
TEST(SimulatorSettingsRanges, AnUnknownSettingSuggestsTheNearestKnownOne) {
  Diagnostics diagnostics;
  settingsFromJson(R"({"presure_mmhg": 90, "qqq": 1})", diagnostics, {}, "case.json");
  ASSERT_EQ(diagnostics.problems().size(), 2u);
  EXPECT_EQ(diagnostics.problems()[0].where, "simulation.presure_mmhg");
  EXPECT_EQ(diagnostics.problems()[0].what,
            "unknown simulation setting; did you mean \"pressure_mmhg\"?");
  EXPECT_EQ(diagnostics.problems()[1].what, "unknown simulation setting");
}

// A key without its unit is more than two edits from the key; the key it starts is the guess,
// unless several start with it ("contact" -> contact_thickness_mm, contact_margin_mm, ...).
TEST(SimulatorSettingsRanges, AKeyWithoutItsUnitSuggestsTheKeyWithIt) {
  Diagnostics diagnostics;
  settingsFromJson(R"({"youngs_modulus": 2, "pressure": 90, "contact_margin": 0.1})", diagnostics,
                   {}, "case.json");
  ASSERT_EQ(diagnostics.problems().size(), 3u);
  std::map<std::string, std::string> what;
  for (const auto& p : diagnostics.problems()) what[p.where] = p.what;
  EXPECT_EQ(what["simulation.youngs_modulus"],
            "unknown simulation setting; did you mean \"youngs_modulus_mpa\"?");
  EXPECT_EQ(what["simulation.pressure"],
            "unknown simulation setting; did you mean \"pressure_mmhg\"?");
  EXPECT_EQ(what["simulation.contact_margin"],
            "unknown simulation setting; did you mean \"contact_margin_mm\"?");
}

TEST(SimulatorSettingsRanges, AreaFloorIsReadFromJsonAndZeroDisablesIt) {
  Diagnostics diagnostics;
  const SimulationSettings s =
      settingsFromJson(R"({"area_floor_fraction": 0})", diagnostics, {}, "case.json");
  EXPECT_TRUE(diagnostics.problems().empty());
  EXPECT_EQ(s.area_floor_fraction, 0.0);
  EXPECT_EQ(SimulationSettings{}.area_floor_fraction, 0.5);
}

TEST(SimulatorSettingsRanges, EdgeContactIsOptInAndReadFromJson) {
  EXPECT_FALSE(SimulationSettings{}.edge_contact);
  Diagnostics diagnostics;
  const SimulationSettings s =
      settingsFromJson(R"({"edge_contact": true})", diagnostics, {}, "case.json");
  EXPECT_TRUE(diagnostics.problems().empty());
  EXPECT_TRUE(s.edge_contact);
  Diagnostics bad;
  settingsFromJson(R"({"edge_contact": "yes"})", bad, {}, "case.json");
  ASSERT_EQ(bad.problems().size(), 1u);
  EXPECT_EQ(bad.problems()[0].where, "simulation.edge_contact");
}

TEST(SimulatorSettingsRanges, JsonOutOfRangeValuesAreDiagnosedWithFileKeyAndProblem) {
  Diagnostics diagnostics;
  settingsFromJson(R"({"pressure_mmhg": 1e300, "ramp_ms": 2.0})", diagnostics, {},
                   "cases/x/case.json");
  ASSERT_EQ(diagnostics.problems().size(), 1u);
  const Problem& p = diagnostics.problems()[0];
  EXPECT_EQ(p.file, "cases/x/case.json");
  EXPECT_EQ(p.where, "simulation.pressure_mmhg");
  EXPECT_NE(p.what.find("out of range"), std::string::npos) << p.what;
}

TEST(SimulatorSettingsRanges, SimulateRefusesOutOfRangeSettingsWithoutRunning) {
  SimulationModel model;
  model.V_rest = Eigen::MatrixXd::Identity(3, 3);
  model.F = Eigen::RowVector3i(0, 1, 2);
  SimulationSettings s;
  s.pressure_mmhg = 1e300;
  const SimulationResult r = simulate(model, s);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find("pressure_mmhg"), std::string::npos) << r.error;
  EXPECT_EQ(r.steps, 0);
  EXPECT_EQ(r.V.size(), 0);
}

}  // namespace
}  // namespace chordfit
