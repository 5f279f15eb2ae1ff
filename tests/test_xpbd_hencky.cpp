// A pressurised clamped circular membrane must match Hencky's large-deflection solution
// (Hencky 1915; coefficient for nu = 0.3 from Fichter 1997, NASA TP-3658):
//   w0 = 0.662 a (p a / (E h))^(1/3).
// This checks the compliance mapping of material.h and that the XPBD solve converges to the
// elastic equilibrium (not to an iteration-count-dependent stiffness).
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "core/material.h"
#include "core/simulator.h"
#include "tests/test_sheets.h"

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
  settings.tolerance_mm = 1e-6;  // tight: the deflection is compared to 3 %, not to 1e-4
  settings.max_steps = 100000;
  return simulate(model, settings);
}

TEST(XpbdHencky, ClampedDiscDeflectionMatchesHenckyAtTwoPressures) {
  // The issue allows 15 %; measured 0.5 and 1.5 % (0.50 and 1.47 %). Deflection goes as
  // (E h)^(-1/3), so 15 % would let the stiffness mapping be off by -39 to +52 %; 3 % holds it to
  // -8.5 to +9.6 %, with twice the larger measured error as margin.
  constexpr double kTolerance = 0.03;
  constexpr double kRadius = 10.0;  // mm
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

// A membrane strip stretched by 1 % along its length narrows by the in-plane Poisson ratio
// material.h documents: 1/3 for the spring lattice alone, (c + K_a) / (3 c + K_a) = 0.39 with
// the default area term (effectivePoissonRatio). The strip is 6x as long as wide, its short
// ends held and moved apart over the ramp, its long edges free; measured at the middle.
TEST(XpbdMembrane, UniaxialStretchNarrowsByTheDocumentedPoissonRatio) {
  constexpr double kWidth = 10.0, kStrain = 0.01;
  constexpr int kRows = 6;
  const double edge = 2.0 * kWidth / kRows / std::sqrt(3.0);
  const int columns = static_cast<int>(6.0 * kWidth / edge) + 1;
  for (double area_bulk_fraction : {0.0, 0.1}) {
    SimulationModel model;
    testing::makeTriangleLattice(columns, kRows, edge, model.V_rest, model.F);
    std::vector<int> ends;
    for (int r = 0; r <= kRows; ++r)
      ends.push_back(r * columns), ends.push_back(r * columns + columns - 1);
    Eigen::MatrixXd stretched(ends.size(), 3);
    for (size_t k = 0; k < ends.size(); ++k) {
      stretched.row(k) = model.V_rest.row(ends[k]);
      stretched(k, 0) *= 1.0 + kStrain;  // the lattice starts at x = 0
    }
    testing::holdVertices(model, ends, &stretched);
    SimulationSettings settings;
    settings.material.area_bulk_fraction = area_bulk_fraction;
    settings.pressure_mmhg = 1e-9;  // in-plane load only (the pressure must be > 0)
    settings.contact = false;
    settings.tolerance_mm = 1e-9;
    settings.max_steps = 100000;
    const SimulationResult result = simulate(model, settings);
    ASSERT_TRUE(result.ok()) << result.error;
    EXPECT_TRUE(result.converged);
    const int middle = columns / 2;
    const double width = result.V(kRows * columns + middle, 1) - result.V(middle, 1);
    const double poisson = -(width / (kRows * 0.5 * std::sqrt(3.0) * edge) - 1.0) / kStrain;
    const double expected = effectivePoissonRatio(area_bulk_fraction);
    std::printf("[ membrane ] area_bulk_fraction %.1f: Poisson ratio %.4f, documented %.4f\n",
                area_bulk_fraction, poisson, expected);
    EXPECT_NEAR(poisson, expected, 0.02 * expected);
  }
}

}  // namespace
}  // namespace chordfit
