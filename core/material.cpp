#include "core/material.h"

#include <cmath>
#include <limits>

namespace chordfit {

double membraneModulus(const LeafletMaterial& m) { return m.youngs_modulus_mpa * m.thickness_mm; }

double bendingRigidity(const LeafletMaterial& m) {
  const double h = m.thickness_mm;
  return m.youngs_modulus_mpa * h * h * h / (12.0 * (1.0 - m.poisson_ratio * m.poisson_ratio));
}

double springScale(double f) {
  // With x = c / Y: 4x(2x + f) = 3x + f  <=>  8x^2 + (4f - 3)x - f = 0, positive root.
  const double b = 4.0 * f - 3.0;
  const double x = (-b + std::sqrt(b * b + 32.0 * f)) / 16.0;
  return x / (3.0 / 8.0);
}

double effectivePoissonRatio(double f) {
  const double c = springScale(f) * 3.0 / 8.0;  // in units of Y
  return (c + f) / (3.0 * c + f);
}

double edgeCompliance(const LeafletMaterial& m, double adjacent_area, double rest_length) {
  const double k = springScale(m.area_bulk_fraction) * membraneModulus(m) * adjacent_area /
                   (rest_length * rest_length);
  return 1.0 / k;
}

double bendingCompliance(const LeafletMaterial& m, double adjacent_area, double rest_length) {
  const double k =
      m.flexural_modulus_factor * bendingRigidity(m) * rest_length * rest_length / adjacent_area;
  return 1.0 / k;
}

double areaCompliance(const LeafletMaterial& m, double rest_area) {
  const double bulk = m.area_bulk_fraction * membraneModulus(m);
  if (bulk <= 0.0) return std::numeric_limits<double>::infinity();
  return rest_area / bulk;
}

double lumpedMass(const LeafletMaterial& m, double vertex_area) {
  return m.density_g_per_cm3 * kGramPerMm3PerGramPerCm3 * m.thickness_mm * vertex_area;
}

}  // namespace chordfit
