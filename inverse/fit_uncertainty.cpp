#include "inverse/fit_uncertainty.h"

#include <cmath>

#include <Eigen/Cholesky>

#include "inverse/robust_loss.h"

namespace chordfit::inverse {

namespace {

constexpr double kCorrelationCutoff = 0.05;

// tau = 1 + 2 sum_k rho_k of e along the runs (see the header), the sum stopping at the first
// lag whose autocorrelation falls below the cutoff or that no run is long enough for.
double correlationTime(const Eigen::VectorXd& e, const std::vector<int>& runs) {
  if (e.size() < 2) return 1.0;
  const Eigen::VectorXd d = e.array() - e.mean();
  const double variance = d.squaredNorm() / static_cast<double>(d.size());
  if (!(variance > 0.0)) return 1.0;
  double tau = 1.0;
  for (int lag = 1;; ++lag) {
    double sum = 0.0;
    long pairs = 0;
    Eigen::Index start = 0;
    for (int run : runs) {
      for (Eigen::Index i = start; i + lag < start + run; ++i) sum += d(i) * d(i + lag), ++pairs;
      start += run;
    }
    if (pairs == 0) break;
    const double rho = sum / static_cast<double>(pairs) / variance;
    if (rho < kCorrelationCutoff) break;
    tau += 2.0 * rho;
  }
  return tau;
}

}  // namespace

FitUncertainty fitUncertainty(const Eigen::MatrixXd& J, const Eigen::VectorXd& data,
                              const std::vector<int>& point_runs, double huber_delta,
                              const Eigen::MatrixXd& A, const Eigen::VectorXd& x,
                              const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  FitUncertainty u;
  const Eigen::Index m = J.rows(), n = J.cols();
  if (data.size() != m || x.size() != n || lower.size() != n || upper.size() != n ||
      (A.size() > 0 && A.cols() != n)) {
    u.error = "uncertainty: inconsistent sizes";
    return u;
  }
  if (m <= n) {
    u.error = "uncertainty: needs more data residuals than parameters";
    return u;
  }
  Eigen::Index point_count = 0;
  for (int run : point_runs) point_count += run;
  if (point_count > m) {
    u.error = "uncertainty: more tracing points than data residuals";
    return u;
  }
  const Eigen::VectorXd weight = huberWeights(data, point_count, huber_delta);
  const double sigma2 = (weight.array() * data.array().square()).sum() / static_cast<double>(m - n);
  u.sigma_mm = std::sqrt(sigma2);
  const Eigen::VectorXd weighted = weight.cwiseSqrt().cwiseProduct(data);
  u.correlation_time = correlationTime(weighted.head(point_count), point_runs);
  const Eigen::MatrixXd Jw = weight.cwiseSqrt().asDiagonal() * J;
  Eigen::MatrixXd H = Jw.transpose() * Jw;
  if (A.size() > 0) H += A.transpose() * A;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
      (ldlt.vectorD().array() <= 0.0).any()) {
    u.error = "uncertainty: the fit's normal matrix is singular (a parameter moves nothing)";
    return u;
  }
  const Eigen::MatrixXd C =
      u.correlation_time * sigma2 * ldlt.solve(Eigen::MatrixXd::Identity(n, n));
  u.sd = C.diagonal().cwiseMax(0.0).cwiseSqrt();
  u.sensitivity = J.colwise().norm().transpose();
  u.at_bound.resize(n);
  for (Eigen::Index p = 0; p < n; ++p)
    u.at_bound[p] = x(p) <= lower(p) + 1e-9 || x(p) >= upper(p) - 1e-9;
  return u;
}

}  // namespace chordfit::inverse
