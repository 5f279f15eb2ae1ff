#include "inverse/nlopt_driver.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <new>
#include <vector>

#include <nlopt.hpp>

#include "core/counted.h"

namespace chordfit::inverse {

namespace {

nlopt::algorithm algorithmOf(const std::string& name) {
  if (name == "bobyqa") return nlopt::LN_BOBYQA;
  if (name == "cobyla") return nlopt::LN_COBYLA;
  if (name == "sbplx") return nlopt::LN_SBPLX;
  return nlopt::GN_CRS2_LM;
}

struct CallbackState {
  FitObjective* objective = nullptr;
  std::string stage;
  int evaluations = 0;
  double failure_cost = 1e6;  // returned for a failed closure (finite: BOBYQA needs numbers)
  bool budget_reached = false;
};

double cost(unsigned n, const double* x, double* gradient, void* data) {
  (void)gradient;  // derivative-free algorithms only
  auto& state = *static_cast<CallbackState*>(data);
  const Eigen::VectorXd point = Eigen::Map<const Eigen::VectorXd>(x, n);
  if (state.objective->cached(point) == nullptr && !state.objective->budgetAllows(1)) {
    state.budget_reached = true;
    throw nlopt::forced_stop();
  }
  const auto evaluation = state.objective->evaluate(point);
  const double value = evaluation->ok() ? evaluation->cost : state.failure_cost;
  // NLopt gets the finite failure cost; the history says the closure failed (NaN).
  state.objective->recordIteration(state.stage, ++state.evaluations, evaluation->ok() ? value : NAN,
                                   evaluation->ok() ? evaluation->mean_deviation_mm : NAN);
  return value;
}

}  // namespace

Termination NloptDriver::minimize(FitObjective& objective, const OptimizerSettings& settings) {
  const FitParameterization& parameters = objective.residual().parameters();
  const int n = parameters.size();
  if (n == 0) return {"nothing to fit (every cord is locked)"};
  nlopt::opt opt(algorithmOf(algorithm_), static_cast<unsigned>(n));
  auto toStd = [](const Eigen::VectorXd& v) {
    return std::vector<double>(v.data(), v.data() + v.size());
  };
  opt.set_lower_bounds(toStd(parameters.lower()));
  opt.set_upper_bounds(toStd(parameters.upper()));
  std::vector<double> step(n);
  for (int p = 0; p < n; ++p) {
    step[p] = parameters.isScale(p) ? settings.initial_scale_step : settings.initial_tip_step_mm;
    // BOBYQA needs bounds at least two initial steps apart ("insufficient space between the
    // bounds" after the pre-fits, with --scale-bounds 0.99,1.01): a narrower box gets a smaller
    // first step, kept below half the width (at exactly half, NLopt's rescaling of group
    // factors still failed the check by rounding).
    step[p] = std::min(step[p], 0.45 * (parameters.upper()(p) - parameters.lower()(p)));
  }
  opt.set_initial_step(step);
  opt.set_ftol_rel(settings.function_tolerance);
  opt.set_xtol_rel(settings.parameter_tolerance);
  // NLopt counts cached points too; the cost callback enforces the forward-run budget itself.
  opt.set_maxeval(std::max(1, objective.maxSims() - objective.forwardSims() + 1));
  nlopt::srand(settings.random_seed);  // crs2 draws its population from NLopt's generator

  CallbackState state;
  state.objective = &objective;
  state.stage = algorithm_;
  if (const auto start = objective.evaluate(objective.startPoint()); start->ok()) {
    state.failure_cost = std::max(1e6, 100.0 * start->cost);
  }
  opt.set_min_objective(cost, &state);

  std::vector<double> x = toStd(objective.startPoint());
  double value = 0.0;
  std::string message;
  bool budget_spent = false;
  try {
    const nlopt::result result = opt.optimize(x, value);
    switch (result) {
      case nlopt::FTOL_REACHED: {
        char text[96];
        std::snprintf(text, sizeof text,
                      "converged: relative cost change below ftol (%g) between two evaluations",
                      settings.function_tolerance);
        message = text;
        break;
      }
      case nlopt::XTOL_REACHED:
        message = "converged: relative step below xtol";
        break;
      case nlopt::MAXEVAL_REACHED:
        // maxeval is set from the remaining budget but also counts revisits of cached points,
        // which cost no closure: a budget stop only when no closure is left.
        message = "stopped: NLopt's evaluation limit reached with " +
                  counted(objective.maxSims() - objective.forwardSims(), "closure") +
                  " of the budget left (NLopt also counts revisits of points already "
                  "closed, which cost none)";
        budget_spent = !objective.budgetAllows(1);
        break;
      default:
        message = "nlopt result " + std::to_string(static_cast<int>(result));
    }
  } catch (const nlopt::forced_stop&) {
    message = "budget of " + counted(objective.maxSims(), "forward run") + " reached";
  } catch (const nlopt::roundoff_limited&) {
    message = "stopped: roundoff limited (the cost is flat at the closure's precision)";
  } catch (const std::bad_alloc&) {
    message = "stopped: out of memory";
  } catch (const std::exception& e) {
    message = std::string("stopped: nlopt failure: ") + e.what();
  }
  if (budget_spent || state.budget_reached || objective.budgetRefused()) {
    return {"budget of " + counted(objective.maxSims(), "forward run") + " reached", true};
  }
  return {message};
}

}  // namespace chordfit::inverse
