// Huber's robust loss in Ceres' convention (ceres::HuberLoss, Ceres Solver documentation,
// "Modeling Non-linear Least Squares: LossFunction"): for a squared residual s = r^2,
//   rho(s) = s                       if s <= delta^2
//          = 2 delta sqrt(s) - delta^2 otherwise,
// so a residual beyond delta counts linearly, not quadratically. The fit's cost is
// 1/2 sum_i rho(r_i^2) over the data residuals plus 1/2 sum_j r_j^2 over the regularisation
// residuals, the same number Ceres reports, so every driver's cost history is comparable.
#pragma once

#include <cmath>

namespace chordfit::inverse {

inline double huberRho(double squared_residual, double delta) {
  if (squared_residual <= delta * delta) return squared_residual;
  return 2.0 * delta * std::sqrt(squared_residual) - delta * delta;
}

}  // namespace chordfit::inverse
