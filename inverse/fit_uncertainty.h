// Which fitted parameters the tracings determine, and how well: a local (Laplace, or
// linearised least-squares) approximation of the fit's uncertainty at its best point
// (Seber and Wild 1989, "Nonlinear Regression", sec. 2.1; the covariance Ceres' Covariance
// class computes, scaled by the residual variance).
//
// With J the data Jacobian at the best point (central differences, finite_difference.h),
// r the data residuals there, A the regularisation Jacobian (forward_residual.h):
//   - robust weights: a tracing-point residual beyond Huber's delta counts with weight
//     w_i = delta / |r_i| (the iteratively reweighted least-squares form of the loss), so
//     J_w = diag(sqrt(w)) J; section residuals have w = 1;
//   - residual variance sigma^2 = sum_i w_i r_i^2 / (m - n) over the m data residuals and n
//     parameters: tracing noise plus whatever the model cannot fit (a coarse mesh, tissue it
//     does not model);
//   - correlation: what the model cannot fit is smooth along a tracing, so neighbouring point
//     residuals are not independent and the m residuals carry fewer independent pieces of
//     information. The variance is inflated by the integrated autocorrelation time
//       tau = 1 + 2 sum_{k >= 1} rho_k
//     of the weighted residuals along each tracing polyline (pooled over polylines, deviations
//     from their mean; the sum stops at the first lag with rho_k < 0.05), the effective-sample
//     -size correction of correlated regression residuals (Bayley and Hammersley 1946; Sokal
//     1997 for the truncated sum). Measured on the cohort without it, the errors of the cords
//     the fit called determined were a median 4.6 of its SDs (docs/fitting.md, "Uncertainty");
//   - covariance C = tau sigma^2 (J_w^T J_w + A^T A)^-1: the whole cost as a negative log
//     likelihood with that variance, the regularisation acting as a weak Gaussian prior, so a
//     parameter the data do not see keeps a finite, large SD set by the prior;
//   - SD_p = sqrt(C_pp), and the data sensitivity |J(:, p)|_2: how far, in the root sum of
//     squares over all data residuals, the residuals move per unit of parameter p.
// A parameter at one of its bounds is flagged: the linear approximation ignores the bound.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace chordfit::inverse {

struct FitUncertainty {
  Eigen::VectorXd sd;             // per parameter, in the parameter's units
  Eigen::VectorXd sensitivity;    // per parameter, |J(:, p)|_2 (mm per unit parameter)
  std::vector<bool> at_bound;     // parameter within 1e-9 of a bound
  double sigma_mm = 0.0;          // residual SD sigma (mm)
  double correlation_time = 1.0;  // tau (>= 1), in tracing points
  int jacobian_sims = 0;          // closures run for J (0 when it came from the optimiser)
  int unsettled_sims = 0;         // of jacobian_sims: closures that reached their step cap
  std::string error;              // J could not be computed or the system is singular
  bool ok() const { return error.empty() && sd.size() > 0; }
};

// The uncertainty from the Jacobian J (#data by #parameters) at the point x with data
// residuals `data` (#data; the first sum(point_runs) are tracing points under Huber's loss
// with `huber_delta`, in runs of consecutive points along one polyline each, the rest
// unweighted and uncorrelated), regularisation Jacobian A (#reg by #parameters) and bounds.
// Needs #data > #parameters.
FitUncertainty fitUncertainty(const Eigen::MatrixXd& J, const Eigen::VectorXd& data,
                              const std::vector<int>& point_runs, double huber_delta,
                              const Eigen::MatrixXd& A, const Eigen::VectorXd& x,
                              const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

}  // namespace chordfit::inverse
