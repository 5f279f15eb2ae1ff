// A pressurised clamped circular membrane must match Hencky's large-deflection solution
// (Hencky 1915; coefficient for nu = 0.3 from Fichter 1997, NASA TP-3658):
//   w0 = 0.662 a (p a / (E h))^(1/3).
// This checks the compliance mapping of material.h and that the XPBD solve converges to the
// elastic equilibrium (not to an iteration-count-dependent stiffness).
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "core/material.h"
#include "core/simulator.h"
#include "tests/test_xpbd_disc.h"

namespace chordfit {
namespace {

double henckyCentreDeflection(double a, double p, double E, double h) {
  return 0.662 * a * std::cbrt(p * a / (E * h));
}

SimulationResult pressuriseDisc(double pressure_mmhg, const LeafletMaterial& material,
                                double radius, int rings) {
  const SimulationModel model = testing::clampedDiscModel(radius, rings);
  SimulationSettings settings;
  settings.material = material;
  settings.pressure_mmhg = pressure_mmhg;
  settings.contact = false;
  settings.tolerance_mm = 1e-6;  // tight: the deflection is compared to 15 %, not to 1e-4
  settings.max_steps = 100000;
  return simulate(model, settings);
}

TEST(XpbdHencky, ClampedDiscDeflectionMatchesHenckyAtTwoPressures) {
  constexpr double kTolerance = 0.15;  // relative error allowed by the design
  constexpr double kRadius = 10.0;     // mm
  // Thin, stiff membrane so that bending is negligible (w0 / h >> 1), as Hencky assumes;
  // deflections stay moderate (w0 / a ~ 0.15 - 0.25).
  LeafletMaterial material;
  material.youngs_modulus_mpa = 30.0;
  material.thickness_mm = 0.1;
  for (double pressure_mmhg : {25.0, 100.0}) {
    const SimulationResult result = pressuriseDisc(pressure_mmhg, material, kRadius, 12);
    ASSERT_TRUE(result.ok()) << result.error;
    EXPECT_TRUE(result.converged);
    const double w0 = result.V(0, 2);  // vertex 0 is the centre
    const double expected = henckyCentreDeflection(
        kRadius, mmHgToMpa(pressure_mmhg), material.youngs_modulus_mpa, material.thickness_mm);
    const double error = std::abs(w0 - expected) / expected;
    std::printf(
        "[ hencky   ] p = %5.1f mmHg: w0 = %.4f mm, Hencky %.4f mm, error %.1f %% "
        "(%d steps, %.3f s)\n",
        pressure_mmhg, w0, expected, 100.0 * error, result.steps, result.seconds);
    EXPECT_LT(error, kTolerance) << "p = " << pressure_mmhg << " mmHg";
  }
}

TEST(XpbdHencky, TextbookXpbdWithFewIterationsIsTooSoftWhichWarmStartingFixes) {
  // Documents why lambda is warm-started (xpbd_constraints.h): at the default time step the
  // textbook scheme (lambda reset each step, 2 iterations) leaves the membrane too soft.
  constexpr double kRadius = 10.0;
  LeafletMaterial material;
  material.youngs_modulus_mpa = 30.0;
  material.thickness_mm = 0.1;
  const SimulationModel model = testing::clampedDiscModel(kRadius, 12);
  SimulationSettings settings;
  settings.material = material;
  settings.contact = false;
  settings.tolerance_mm = 1e-6;
  settings.max_steps = 100000;
  const double expected =
      henckyCentreDeflection(kRadius, mmHgToMpa(settings.pressure_mmhg),
                             material.youngs_modulus_mpa, material.thickness_mm);
  settings.warm_start_lambda = false;
  const SimulationResult textbook = simulate(model, settings);
  settings.warm_start_lambda = true;
  const SimulationResult warm = simulate(model, settings);
  ASSERT_TRUE(textbook.ok() && warm.ok());
  const double textbook_error = std::abs(textbook.V(0, 2) - expected) / expected;
  const double warm_error = std::abs(warm.V(0, 2) - expected) / expected;
  EXPECT_LT(warm_error, 0.5 * textbook_error);
}

}  // namespace
}  // namespace chordfit
