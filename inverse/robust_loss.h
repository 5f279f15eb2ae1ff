// Huber's robust loss in Ceres' convention (ceres::HuberLoss, Ceres Solver documentation,
// "Modeling Non-linear Least Squares: LossFunction"): for a squared residual s = r^2,
//   rho(s) = s                       if s <= delta^2
//          = 2 delta sqrt(s) - delta^2 otherwise,
// so a residual beyond delta counts linearly, not quadratically. The fit's cost is
// 1/2 sum_i rho(r_i^2) over the data residuals plus 1/2 sum_j r_j^2 over the regularisation
// residuals, the same number Ceres reports, so every driver's cost history is comparable.
#pragma once

#include <cmath>

#include <Eigen/Core>

namespace chordfit::inverse {

inline double huberRho(double squared_residual, double delta) {
  if (squared_residual <= delta * delta) return squared_residual;
  return 2.0 * delta * std::sqrt(squared_residual) - delta * delta;
}

// The iteratively reweighted least-squares weights of Huber's loss over the data residuals:
// w_i = 1 inside delta and delta / |r_i| beyond, for the first point_count residuals (tracing
// points); 1 for the rest (section residuals, no loss). With them 1/2 sum w_i r_i^2 has the
// gradient of 1/2 sum rho(r_i^2) (Holland and Welsch 1977).
inline Eigen::VectorXd huberWeights(const Eigen::VectorXd& data, Eigen::Index point_count,
                                    double delta) {
  Eigen::VectorXd weight = Eigen::VectorXd::Ones(data.size());
  for (Eigen::Index i = 0; i < point_count && i < data.size(); ++i) {
    const double r = std::abs(data(i));
    if (r > delta) weight(i) = delta / r;
  }
  return weight;
}

}  // namespace chordfit::inverse
