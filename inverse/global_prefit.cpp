#include "inverse/global_prefit.h"

#include <algorithm>
#include <cmath>

#include "inverse/finite_difference.h"

namespace chordfit::inverse {

CordSet scaleFreeCords(const CordSet& seed, double factor) {
  CordSet set = seed;
  if (factor == 1.0) return set;
  for (Cord& cord : set.cords) {
    if (cord.locked || cord.provenance == Provenance::kManual) continue;
    cord.rest_length *= factor;
  }
  return set;
}

std::vector<ForwardEvaluation> closeCordSets(const ValveCase& valve_case,
                                             const std::vector<CordSet>& sets,
                                             const ForwardResidual& residual, int threads) {
  const Eigen::VectorXd no_regularisation;
  std::vector<ForwardEvaluation> out(sets.size());
  parallelFor(static_cast<int>(sets.size()), threads, [&](int i) {
    ForwardEvaluation& e = out[i];
    const SimulationResult r = simulateClosure(valve_case, sets[i], residual.settings());
    if (!r.ok()) {
      e.error = r.error;
      return;
    }
    e.converged = r.converged;
    e.closed_V = r.V;
    e.data = residual.dataResiduals(r.V);
    e.cost = residual.cost(e.data, no_regularisation);
    e.mean_deviation_mm = e.data.size() > 0 ? e.data.mean() : 0.0;
  });
  return out;
}

PrefitResult globalScalePrefit(const ValveCase& valve_case, const CordSet& seed,
                               const ForwardEvaluation& seed_evaluation,
                               const ParameterBounds& bounds, const ForwardResidual& residual,
                               const PrefitOptions& options) {
  PrefitResult result;
  result.start = seed;
  result.best = seed_evaluation;
  const Eigen::VectorXd no_regularisation;
  const double seed_cost = residual.cost(seed_evaluation.data, no_regularisation);

  auto run = [&](const std::vector<double>& factors) {
    std::vector<CordSet> sets;
    for (double factor : factors) sets.push_back(scaleFreeCords(seed, factor));
    std::vector<ForwardEvaluation> out = closeCordSets(valve_case, sets, residual, options.threads);
    for (std::size_t i = 0; i < factors.size(); ++i)
      out[i].x = Eigen::VectorXd::Constant(1, factors[i]);
    result.forward_sims += static_cast<int>(factors.size());
    return out;
  };
  double best_cost = seed_cost;
  auto consider = [&](const std::vector<double>& factors) {
    std::vector<ForwardEvaluation> evaluations = run(factors);
    for (std::size_t i = 0; i < factors.size(); ++i) {
      result.factors.push_back(factors[i]);
      result.costs.push_back(evaluations[i].ok() ? evaluations[i].cost : NAN);
      if (evaluations[i].ok() && evaluations[i].cost < best_cost) {
        best_cost = evaluations[i].cost;
        result.factor = factors[i];
        result.best = std::move(evaluations[i]);
      }
    }
  };

  const int points = std::max(2, options.points);
  const double spacing = (bounds.scale_upper - bounds.scale_lower) / (points - 1);
  std::vector<double> grid;
  for (int i = 0; i < points; ++i) {
    const double factor = bounds.scale_lower + i * spacing;
    if (std::abs(factor - 1.0) > 1e-9) grid.push_back(factor);  // 1 = the seed, already run
  }
  consider(grid);
  std::vector<double> refine;
  const int half = std::max(1, options.refine_points / 2);
  for (int k = 1; k <= half; ++k) {
    const double offset = spacing * k / (half + 1);
    for (double factor : {result.factor - offset, result.factor + offset}) {
      if (factor >= bounds.scale_lower && factor <= bounds.scale_upper) refine.push_back(factor);
    }
  }
  std::sort(refine.begin(), refine.end());
  consider(refine);
  result.start = scaleFreeCords(seed, result.factor);
  return result;
}

}  // namespace chordfit::inverse
