#include "inverse/cord_optimisation.h"

#include <chrono>
#include <cmath>

#include "core/metrics.h"
#include "inverse/fit_cords.h"

namespace chordfit::inverse {

namespace {

// The slack release after the optimiser (slack_release.h): cords slack at the optimiser's best
// are raised to their kind's typical scale, kept when a full closure fits as well. Returns the
// closure the fit keeps: the release's when kept, else `best`.
std::shared_ptr<const ForwardEvaluation> releaseSlackCords(
    Optimisation& run, std::shared_ptr<const ForwardEvaluation> best, const CordSet& seed,
    const FitOptions& options, const OptimisationStart& from,
    FitObjective::Clock::time_point clock_start) {
  const FitParameterization& parameters = *run.parameters;
  const ForwardResidual& residual = *run.residual;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(best->regularisation.size());
  const CordSet at_best = parameters.apply(best->x);
  const Eigen::VectorXi vertex_segment = openStateSegments(run.working_case.mesh);
  std::vector<int> cord_segment;
  for (const Cord& cord : at_best.cords) cord_segment.push_back(vertex_segment(cord.vertex));
  run.release.proposal = proposeSlackRelease(
      at_best, seed, closedSpans(at_best, residual.cordInsertions(), best->closed_V), cord_segment,
      atypicalSegments(run.working_case, best->closed_V, from.rescaled_segments),
      options.bounds.scale_upper);
  const SlackReleaseProposal& proposal = run.release.proposal;
  if (proposal.empty()) return best;
  // Free non-manual cords are parameters of their own in the per-cord modes.
  Eigen::VectorXd x = best->x;
  for (std::size_t i = 0; i < proposal.cords.size(); ++i) {
    const int parameter = parameters.cordParameter()[proposal.cords[i]];
    if (parameter >= 0) x(parameter) = proposal.scales[i];
  }
  auto released = std::make_shared<ForwardEvaluation>(residual.evaluate(x));
  ++run.forward_sims;
  SlackReleaseOutcome& release = run.release;
  release.optimiser_data_cost = residual.cost(best->data, zero);
  if (released->ok()) {
    release.data_cost = residual.cost(released->data, zero);
    release.kept = release.data_cost <=
                   release.optimiser_data_cost * (1.0 + options.slack_release.cost_tolerance);
  } else {
    release.error = released->error;
  }
  const IterationRecord r =
      closureRecord("release", 0, *released, release.kept ? released->cost : best->cost,
                    run.forward_sims, clock_start);
  run.history.push_back(r);
  if (options.on_iteration) options.on_iteration(r);
  return release.kept ? released : best;
}

}  // namespace

IterationRecord closureRecord(const std::string& stage, int iteration, const ForwardEvaluation& e,
                              double best_cost, int forward_sims,
                              FitObjective::Clock::time_point clock_start) {
  return {stage,
          iteration,
          e.ok() ? e.cost : NAN,
          best_cost,
          e.ok() ? e.mean_deviation_mm : NAN,
          forward_sims,
          std::chrono::duration<double>(FitObjective::Clock::now() - clock_start).count()};
}

std::unique_ptr<Optimisation> optimise(const ValveCase& valve_case, const CordSet& seed,
                                       const SimulationSettings& settings,
                                       const FitOptions& options, const OptimisationStart& from,
                                       FitObjective::Clock::time_point clock_start) {
  auto run = std::make_unique<Optimisation>();
  run->working_case = valve_case;
  if (from.tissue.size() > 0) run->working_case.tissue_stiffness = from.tissue;
  run->forward_sims = from.sims_before;
  ForwardEvaluation start_evaluation = from.evaluation;

  run->parameters = std::make_unique<FitParameterization>(run->working_case, from.cords,
                                                          options.mode, options.bounds);
  const FitParameterization& parameters = *run->parameters;
  run->residual =
      std::make_unique<ForwardResidual>(run->working_case, parameters, settings, options.residual);
  const ForwardResidual& residual = *run->residual;
  const bool release_slack = options.slack_release.enabled && parameters.size() > 0 &&
                             options.mode != ParameterMode::kGroups &&
                             run->forward_sims + 2 <= options.max_sims;
  run->release.ran = release_slack;
  run->objective = std::make_unique<FitObjective>(
      residual, options.finite_difference, options.max_sims - (release_slack ? 1 : 0),
      run->forward_sims, clock_start, options.on_iteration);
  FitObjective& objective = *run->objective;
  objective.setProgress(options.on_stage);
  if (!parameters.startClamped()) {
    // The start's closure is already known (the same cords): reuse it, with this
    // parameterisation's x and regularisation (zero at the start).
    start_evaluation.x = parameters.initial();
    start_evaluation.regularisation = residual.regularisation(start_evaluation.x);
    start_evaluation.cost = residual.cost(start_evaluation.data, start_evaluation.regularisation);
    objective.remember(start_evaluation);
  }
  auto optimizer = makeOptimizer(options.optimizer);
  const Termination termination = optimizer->minimize(objective, options.optimizer_settings);
  run->termination = termination.message;
  run->budget_spent = termination.budget_spent;
  run->switched_to_full_closures =
      options.finite_difference.warm_start && !objective.warmDifferences();
  // The drivers count against the optimiser's share; say where the rest of --max-sims went.
  if (release_slack && termination.budget_spent)
    run->termination += "; 1 more of --max-sims " + std::to_string(options.max_sims) +
                        " kept for the slack release";
  for (const IterationRecord& r : objective.history()) run->history.push_back(r);

  auto best = objective.best();
  if (!best) best = objective.evaluate(parameters.initial());
  run->forward_sims = objective.forwardSims();
  if (!best->ok() && objective.budgetRefused() && !objective.best()) {
    run->error = "--max-sims " + std::to_string(options.max_sims) +
                 " leaves no closure for the optimiser's start (the seed, clamped into the "
                 "scale bounds); raise it";
    run->error_is_input = true;
    return run;
  }
  if (!best->ok()) {
    run->error = "closure at the pre-fit start failed: " + best->error;
    return run;
  }
  run->optimiser_best = best;
  run->best =
      release_slack ? releaseSlackCords(*run, best, seed, options, from, clock_start) : best;
  return run;
}

}  // namespace chordfit::inverse
