// A pressurised clamped circular membrane must match Hencky's large-deflection solution
// (Hencky 1915; coefficient for nu = 0.3 from Fichter 1997, NASA TP-3658):
//   w0 = 0.662 a (p a / (E h))^(1/3).
// This checks the compliance mapping of material.h and that the XPBD solve converges to the
// elastic equilibrium (not to an iteration-count-dependent stiffness).
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/material.h"
#include "core/simulator.h"

namespace chordfit {
namespace {

// Flat disc of radius a in the plane z = 0, `rings` concentric rings of 6k vertices
// (k = 1..rings) around a centre vertex, triangles wound counter-clockwise seen from +z.
// Returns the boundary (outermost ring) in `boundary`.
void makeDisc(double a, int rings, Eigen::MatrixXd& V, Eigen::MatrixXi& F,
              Eigen::VectorXi& boundary) {
  std::vector<Eigen::Vector3d> points{Eigen::Vector3d::Zero()};
  std::vector<std::vector<int>> ring_ids{{0}};
  for (int k = 1; k <= rings; ++k) {
    std::vector<int> ids;
    const int count = 6 * k;
    for (int m = 0; m < count; ++m) {
      const double phi = 2.0 * M_PI * m / count;
      ids.push_back(static_cast<int>(points.size()));
      points.emplace_back(a * k / rings * std::cos(phi), a * k / rings * std::sin(phi), 0.0);
    }
    ring_ids.push_back(ids);
  }
  std::vector<Eigen::Vector3i> faces;
  // Zip consecutive rings by angle: advance on whichever ring's next vertex comes first.
  for (int k = 1; k <= rings; ++k) {
    const std::vector<int>& in = ring_ids[k - 1];
    const std::vector<int>& out = ring_ids[k];
    const int ni = static_cast<int>(in.size()), no = static_cast<int>(out.size());
    int i = 0, o = 0;
    while (o < no || (ni > 1 && i < ni)) {
      const double next_in = ni == 1 ? 1e9 : static_cast<double>(i + 1) / ni;
      const double next_out = static_cast<double>(o + 1) / no;
      if (next_out <= next_in && o < no) {
        faces.emplace_back(in[i % ni], out[o], out[(o + 1) % no]);
        ++o;
      } else {
        faces.emplace_back(in[i % ni], out[o % no], in[(i + 1) % ni]);
        ++i;
      }
    }
  }
  V.resize(points.size(), 3);
  for (size_t p = 0; p < points.size(); ++p) V.row(p) = points[p].transpose();
  F.resize(faces.size(), 3);
  for (size_t f = 0; f < faces.size(); ++f) F.row(f) = faces[f].transpose();
  boundary = Eigen::Map<const Eigen::VectorXi>(ring_ids.back().data(), ring_ids.back().size());
}

double henckyCentreDeflection(double a, double p, double E, double h) {
  return 0.662 * a * std::cbrt(p * a / (E * h));
}

// Deflection of the centre vertex of a clamped disc under pressure p (mmHg).
SimulationResult pressuriseDisc(double pressure_mmhg, const LeafletMaterial& material,
                                double radius, int rings) {
  SimulationModel model;
  Eigen::VectorXi boundary;
  makeDisc(radius, rings, model.V_rest, model.F, boundary);
  model.fixed = boundary;
  model.fixed_start.resize(boundary.size(), 3);
  for (int k = 0; k < boundary.size(); ++k) model.fixed_start.row(k) = model.V_rest.row(boundary(k));
  model.fixed_end = model.fixed_start;
  model.tip_start.resize(0, 3);
  model.tip_end.resize(0, 3);
  SimulationSettings settings;
  settings.material = material;
  settings.pressure_mmhg = pressure_mmhg;
  settings.contact = false;
  settings.tolerance_mm = 1e-6;
  settings.max_steps = 200000;
  return simulate(model, settings);
}

TEST(XpbdHencky, ClampedDiscDeflectionMatchesHenckyAtTwoPressures) {
  constexpr double kTolerance = 0.15;  // relative error allowed by the design
  constexpr double kRadius = 10.0;     // mm
  // Thin, stiff membrane so that bending is negligible (w0 / h >> 1), as Hencky assumes.
  LeafletMaterial material;
  material.youngs_modulus_mpa = 30.0;
  material.thickness_mm = 0.1;
  for (double pressure_mmhg : {25.0, 100.0}) {
    const SimulationResult result = pressuriseDisc(pressure_mmhg, material, kRadius, 12);
    ASSERT_TRUE(result.ok()) << result.error;
    EXPECT_TRUE(result.converged);
    const double w0 = result.V(0, 2);  // vertex 0 is the centre
    const double expected =
        henckyCentreDeflection(kRadius, mmHgToMpa(pressure_mmhg), material.youngs_modulus_mpa,
                               material.thickness_mm);
    const double error = std::abs(w0 - expected) / expected;
    std::printf("[ hencky   ] p = %5.1f mmHg: w0 = %.4f mm, Hencky %.4f mm, error %.1f %% "
                "(%d steps, %.3f s)\n",
                pressure_mmhg, w0, expected, 100.0 * error, result.steps, result.seconds);
    EXPECT_LT(error, kTolerance) << "p = " << pressure_mmhg << " mmHg";
  }
}

}  // namespace
}  // namespace chordfit
