#include "inverse/finite_difference.h"

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace chordfit::inverse {

void parallelFor(int count, int threads, const std::function<void(int)>& task) {
  const int workers = std::max(1, std::min(threads, count));
  if (workers == 1) {
    for (int i = 0; i < count; ++i) task(i);
    return;
  }
  std::atomic<int> next{0};
  auto work = [&] {
    for (int i = next++; i < count; i = next++) task(i);
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < workers; ++t) pool.emplace_back(work);
  for (std::thread& t : pool) t.join();
}

JacobianResult centralDifferenceJacobian(const ForwardResidual& residual, const Eigen::VectorXd& x,
                                         const Eigen::MatrixXd& base_closed,
                                         const FiniteDifferenceOptions& options) {
  const int n = static_cast<int>(x.size());
  const FitParameterization& parameters = residual.parameters();
  std::vector<Eigen::VectorXd> sides(2 * n);
  std::vector<std::string> errors(2 * n);
  const Eigen::MatrixXd* start = options.warm_start ? &base_closed : nullptr;
  auto step = [&](int p) {
    return parameters.isScale(p) ? options.scale_step : options.tip_step_mm;
  };
  parallelFor(2 * n, options.threads, [&](int task) {
    const int p = task / 2;
    Eigen::VectorXd xp = x;
    xp(p) += (task % 2 == 0 ? 1.0 : -1.0) * step(p);
    ForwardEvaluation e = residual.evaluate(xp, start);
    if (!e.ok()) {
      errors[task] = parameters.names()[p] + ": " + e.error;
      return;
    }
    sides[task] = std::move(e.data);
  });
  JacobianResult result;
  result.forward_sims = 2 * n;
  for (const std::string& e : errors) {
    if (!e.empty()) {
      result.error = e;
      return result;
    }
  }
  result.J.resize(residual.dataCount(), n);
  for (int p = 0; p < n; ++p) {
    result.J.col(p) = (sides[2 * p] - sides[2 * p + 1]) / (2.0 * step(p));
  }
  return result;
}

}  // namespace chordfit::inverse
