#include "inverse/global_prefit.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/closure_model.h"
#include "core/parallel_for.h"

namespace chordfit::inverse {

CordSet scaleFreeCords(const CordSet& seed, double factor) {
  return scaleFreeCords(seed, factor, factor);
}

CordSet scaleFreeCords(const CordSet& seed, double primary_factor, double secondary_factor) {
  CordSet set = seed;
  for (Cord& cord : set.cords) {
    if (!isFreeNonManual(cord)) continue;
    const double factor = cord.kind == CordKind::kPrimary ? primary_factor : secondary_factor;
    if (factor != 1.0) cord.rest_length *= factor;
  }
  return set;
}

CordSet scaleFreeCords(const CordSet& seed, double primary_factor, double secondary_factor,
                       const ParameterBounds& bounds) {
  CordSet set = scaleFreeCords(seed, primary_factor, secondary_factor);
  for (std::size_t c = 0; c < set.cords.size(); ++c) {
    Cord& cord = set.cords[c];
    if (cord.rest_length == seed.cords[c].rest_length || !(cord.seed_rest_length > 0.0)) continue;
    // A heuristic seed (scale 1) stays inside for every factor within the bounds: unchanged.
    cord.rest_length = std::clamp(cord.rest_length, cord.seed_rest_length * bounds.scale_lower,
                                  cord.seed_rest_length * bounds.scale_upper);
  }
  return set;
}

ForwardEvaluation closeForData(const ValveCase& valve_case, const CordSet& cords,
                               const ForwardResidual& residual) {
  ForwardEvaluation e;
  const SimulationResult r = simulateClosure(valve_case, cords, residual.settings());
  residual.countClosure(r);
  if (!r.ok()) {
    e.error = r.error;
    return e;
  }
  e.converged = r.converged;
  e.closed_V = r.V;
  e.data = residual.dataResiduals(r.V);
  e.cost = residual.cost(e.data, Eigen::VectorXd());
  e.mean_deviation_mm = residual.meanDeviation(r.V, e.data);
  return e;
}

int cheapestBelow(const std::vector<ForwardEvaluation>& evaluations, double cost) {
  int best = -1;
  for (std::size_t i = 0; i < evaluations.size(); ++i) {
    const double best_cost = best < 0 ? cost : evaluations[best].cost;
    if (evaluations[i].ok() && evaluations[i].cost < best_cost) best = static_cast<int>(i);
  }
  return best;
}

std::vector<ForwardEvaluation> closeCordSets(const ValveCase& valve_case,
                                             const std::vector<CordSet>& sets,
                                             const ForwardResidual& residual, int threads,
                                             const std::function<void(int, int)>& on_closure) {
  std::vector<ForwardEvaluation> out(sets.size());
  std::atomic<int> done{0};
  const int total = static_cast<int>(sets.size());
  parallelFor(total, threads, [&](int i) {
    out[i] = closeForData(valve_case, sets[i], residual);
    if (on_closure) on_closure(++done, total);
  });
  return out;
}

namespace {

double gridSpacing(const PrefitOptions& options, const ParameterBounds& bounds) {
  return (bounds.scale_upper - bounds.scale_lower) / (std::max(2, options.points) - 1);
}

// The common stage's grid over the scale bounds, ends included, without the factor 1 (the
// seed, already closed).
std::vector<double> commonGrid(const PrefitOptions& options, const ParameterBounds& bounds) {
  std::vector<double> grid;
  for (int i = 0; i < std::max(2, options.points); ++i) {
    const double factor = bounds.scale_lower + i * gridSpacing(options, bounds);
    if (std::abs(factor - 1.0) > 1e-9) grid.push_back(factor);
  }
  return grid;
}

// Refinement factors on each side of the best grid point.
int refineHalf(const PrefitOptions& options) { return std::max(1, options.refine_points / 2); }

}  // namespace

int commonStageMaxClosures(const PrefitOptions& options, const ParameterBounds& bounds) {
  return static_cast<int>(commonGrid(options, bounds).size()) + 2 * refineHalf(options);
}

PrefitResult globalScalePrefit(const ValveCase& valve_case, const CordSet& seed,
                               const ForwardEvaluation& seed_evaluation,
                               const ParameterBounds& bounds, const ForwardResidual& residual,
                               const PrefitOptions& options) {
  PrefitResult result;
  result.start = seed;
  result.best = seed_evaluation;
  // Every free cord manual (a seed the user edited): every factor gives the seed again.
  if (std::none_of(seed.cords.begin(), seed.cords.end(), isFreeNonManual)) return result;
  const Eigen::VectorXd no_regularisation;
  const double seed_cost = residual.cost(seed_evaluation.data, no_regularisation);

  // Candidates (primary factor, secondary factor), closed in parallel; the best by data cost
  // replaces result.best when it improves on it. Returns every candidate's evaluation.
  double best_cost = seed_cost;
  auto consider_pairs = [&](const std::vector<std::pair<double, double>>& pairs) {
    std::vector<CordSet> sets;
    for (const auto& [p, s] : pairs) sets.push_back(scaleFreeCords(seed, p, s, bounds));
    std::vector<ForwardEvaluation> evaluations =
        closeCordSets(valve_case, sets, residual, options.threads, options.on_closure);
    result.forward_sims += static_cast<int>(pairs.size());
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      evaluations[i].x = Eigen::Vector2d(pairs[i].first, pairs[i].second);
      if (!evaluations[i].ok() || !(evaluations[i].cost < best_cost)) continue;
      best_cost = evaluations[i].cost;
      result.primary_factor = pairs[i].first;
      result.secondary_factor = pairs[i].second;
      result.best = evaluations[i];
    }
    return evaluations;
  };
  auto consider = [&](const std::vector<double>& factors) {
    std::vector<std::pair<double, double>> pairs;
    for (double f : factors) pairs.emplace_back(f, f);
    const std::vector<ForwardEvaluation> evaluations = consider_pairs(pairs);
    for (std::size_t i = 0; i < factors.size(); ++i) {
      result.factors.push_back(factors[i]);
      result.costs.push_back(evaluations[i].ok() ? evaluations[i].cost : NAN);
    }
    result.factor = result.primary_factor;
  };

  const double spacing = gridSpacing(options, bounds);
  consider(commonGrid(options, bounds));
  std::vector<double> refine;
  const int half = refineHalf(options);
  for (int k = 1; k <= half; ++k) {
    const double offset = spacing * k / (half + 1);
    for (double factor : {result.factor - offset, result.factor + offset}) {
      if (factor >= bounds.scale_lower && factor <= bounds.scale_upper) refine.push_back(factor);
    }
  }
  std::sort(refine.begin(), refine.end());
  consider(refine);

  // Kind stage: secondaries, then primaries, each around the current factors.
  const int kind_half = options.kind_points / 2;
  // Only kinds the factors act on: a kind whose cords are all manual or locked would close
  // the same cords again.
  auto has_free = [&](CordKind kind) {
    return std::any_of(seed.cords.begin(), seed.cords.end(),
                       [&](const Cord& c) { return c.kind == kind && isFreeNonManual(c); });
  };
  const bool has_both = has_free(CordKind::kPrimary) && has_free(CordKind::kSecondary);
  result.kind_stage = !has_both       ? KindStage::kOneKindFree
                      : kind_half > 0 ? KindStage::kRan
                                      : KindStage::kNotAsked;
  for (int kind = 0; has_both && kind_half > 0 && kind < 2; ++kind) {
    const bool secondaries = kind == 0;
    std::vector<std::pair<double, double>> pairs;
    for (int k = -kind_half; k <= kind_half; ++k) {
      if (k == 0) continue;
      const double p = result.primary_factor + (secondaries ? 0.0 : 0.5 * k * spacing);
      const double s = result.secondary_factor + (secondaries ? 0.5 * k * spacing : 0.0);
      const double moved = secondaries ? s : p;
      if (moved >= bounds.scale_lower - 1e-12 && moved <= bounds.scale_upper + 1e-12)
        pairs.emplace_back(p, s);
    }
    consider_pairs(pairs);
  }
  result.start = scaleFreeCords(seed, result.primary_factor, result.secondary_factor, bounds);
  return result;
}

}  // namespace chordfit::inverse
