#include "inverse/fit_cords.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "core/carpentier.h"
#include "core/metrics.h"

namespace chordfit::inverse {

namespace {

// One optimisation of the cords from a start: the optimiser, then the slack release. A fit
// runs one, and a second when the tissue retry runs. Heap-held and never moved: the
// parameterisation, residual and objective refer to working_case and to each other.
struct Optimisation {
  ValveCase working_case;  // the case, on the start's tissue
  std::unique_ptr<FitParameterization> parameters;
  std::unique_ptr<ForwardResidual> residual;
  std::unique_ptr<FitObjective> objective;
  std::shared_ptr<const ForwardEvaluation> best, optimiser_best;
  std::string termination;
  bool budget_spent = false;  // the optimiser stopped for the budget
  bool switched_to_full_closures = false;
  SlackReleaseOutcome release;
  std::vector<IterationRecord> history;
  int forward_sims = 0;  // cumulative, every stage of the fit so far
  std::string error;
  bool error_is_input = false;

  double dataCost() const {
    return residual->cost(best->data, Eigen::VectorXd::Zero(best->regularisation.size()));
  }
};

// The history record of a closure run outside the optimiser's iterations (seed, pre-fits,
// slack release, the retry's tissue pre-fit). A failed closure has no cost or deviation: NaN
// in the history (docs/outputs.md).
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

struct OptimisationStart {
  const CordSet& cords;                       // after the pre-fits
  const ForwardEvaluation& evaluation;        // its full closure on `tissue`
  const Eigen::VectorXd& tissue;              // per-vertex factors; empty: the case's own
  const std::vector<int>& rescaled_segments;  // by the segment pre-fit
  int sims_before = 0;
};

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
  if (release_slack) {
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(best->regularisation.size());
    const CordSet at_best = parameters.apply(best->x);
    const Eigen::VectorXi vertex_segment = openStateSegments(run->working_case.mesh);
    std::vector<int> cord_segment;
    for (const Cord& cord : at_best.cords) cord_segment.push_back(vertex_segment(cord.vertex));
    run->release.proposal = proposeSlackRelease(
        at_best, seed, closedSpans(at_best, residual.cordInsertions(), best->closed_V),
        cord_segment, atypicalSegments(run->working_case, best->closed_V, from.rescaled_segments),
        options.bounds.scale_upper);
    const SlackReleaseProposal& proposal = run->release.proposal;
    if (!proposal.empty()) {
      // Free non-manual cords are parameters of their own in the per-cord modes.
      Eigen::VectorXd x = best->x;
      for (std::size_t i = 0; i < proposal.cords.size(); ++i) {
        const int parameter = parameters.cordParameter()[proposal.cords[i]];
        if (parameter >= 0) x(parameter) = proposal.scales[i];
      }
      auto released = std::make_shared<ForwardEvaluation>(residual.evaluate(x));
      ++run->forward_sims;
      SlackReleaseOutcome& release = run->release;
      release.optimiser_data_cost = residual.cost(best->data, zero);
      if (released->ok()) {
        release.data_cost = residual.cost(released->data, zero);
        release.kept = release.data_cost <=
                       release.optimiser_data_cost * (1.0 + options.slack_release.cost_tolerance);
      } else {
        release.error = released->error;
      }
      const IterationRecord r =
          closureRecord("release", 0, *released, run->release.kept ? released->cost : best->cost,
                        run->forward_sims, clock_start);
      run->history.push_back(r);
      if (options.on_iteration) options.on_iteration(r);
      if (run->release.kept) best = released;
    }
  }
  run->best = best;
  return run;
}

// The segment ids of `names` on this mesh (open-state segments; a name without one is left out).
std::vector<int> segmentIds(const ValveMesh& mesh, const std::vector<std::string>& names) {
  const Eigen::VectorXi vertex_segment = openStateSegments(mesh);
  const int count = vertex_segment.size() > 0 ? vertex_segment.maxCoeff() + 1 : 0;
  std::vector<int> ids;
  for (int id = 0; id < count; ++id) {
    const std::string name = segmentName(mesh.leaflet_names, id);
    if (std::find(names.begin(), names.end(), name) != names.end()) ids.push_back(id);
  }
  return ids;
}

}  // namespace

std::string prefitSkipReason(const CordSet& seed) {
  // The cord pre-fits rescale free cords the user did not set; with none, each of their
  // closures would close the seed again.
  const bool any_free =
      std::any_of(seed.cords.begin(), seed.cords.end(), [](const Cord& c) { return !c.locked; });
  if (!any_free || std::any_of(seed.cords.begin(), seed.cords.end(), isFreeNonManual)) return "";
  return "every free cord is manual (the user's values are the optimiser's start)";
}

FitOutcome fitCords(const ValveCase& valve_case, const CordSet& seed,
                    const SimulationSettings& settings, const FitOptions& options) {
  using Clock = FitObjective::Clock;
  const Clock::time_point start = Clock::now();
  FitOutcome outcome;
  outcome.seed = seed;
  if (!makeOptimizer(options.optimizer)) {
    outcome.error = "unknown optimizer \"" + options.optimizer + "\"";
    outcome.error_is_input = true;
    return outcome;
  }
  if (!(options.bounds.scale_lower > 0.0 &&
        options.bounds.scale_lower < options.bounds.scale_upper)) {
    outcome.error = "scale bounds: need 0 < lower < upper";
    outcome.error_is_input = true;
    return outcome;
  }
  auto seconds = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  auto record = [&](const std::string& stage, int iteration, const ForwardEvaluation& e,
                    double best_cost) {
    const IterationRecord r =
        closureRecord(stage, iteration, e, best_cost, outcome.forward_sims, start);
    outcome.history.push_back(r);
    if (options.on_iteration) options.on_iteration(r);
  };

  // Seed closure (full, from the open state): the "before" of every report, of the seed as
  // given. A seed outside the bounds (a manual cord edited past them) is closed as it is here;
  // the optimiser then starts from it clamped into the bounds, and closes that itself.
  const FitParameterization seed_parameters(valve_case, seed, options.mode, options.bounds);
  const ForwardResidual seed_residual(valve_case, seed_parameters, settings, options.residual);
  outcome.seed_evaluation = seed_parameters.startClamped()
                                ? closeForData(valve_case, seed, seed_residual)
                                : seed_residual.evaluate(seed_parameters.initial());
  outcome.forward_sims = 1;
  if (!outcome.seed_evaluation.ok()) {
    outcome.error = "seed closure failed: " + outcome.seed_evaluation.error;
    return outcome;
  }
  record("seed", 0, outcome.seed_evaluation, outcome.seed_evaluation.cost);

  CordSet start_set = seed;
  std::vector<int> segment_prefit_ids;  // segments the segment pre-fit rescaled
  ForwardEvaluation start_evaluation = outcome.seed_evaluation;
  // The pre-fit stages run only when their closures fit in the budget, leaving the final one.
  auto budget_allows = [&](int sims) {
    return outcome.forward_sims + sims + 1 <= options.max_sims;
  };
  // A seed outside the bounds (a manual cord edited past them): the pre-fits start where the
  // optimiser would, from the seed clamped into the bounds. They started from the seed as
  // given: a cord at 0.06 of its length ran every pre-fit closure to the step cap, and the
  // factors were fitted to a valve the optimiser never started from.
  // (Only when a pre-fit stage will run: else the optimiser closes the clamped start itself.)
  const std::string skip_reason = prefitSkipReason(seed);
  const bool prefit_has_cords = skip_reason.empty();
  const bool cord_prefit_runs =
      prefit_has_cords && (options.prefit.enabled || (options.segment_prefit.enabled &&
                                                      options.mode != ParameterMode::kGroups));
  const bool any_prefit =
      (cord_prefit_runs || options.tissue_prefit.enabled) && seed_parameters.size() > 0;
  if (seed_parameters.startClamped() && any_prefit && budget_allows(1)) {
    start_set = seed_parameters.apply(seed_parameters.initial());
    start_evaluation = seed_residual.evaluate(seed_parameters.initial());
    ++outcome.forward_sims;
    if (!start_evaluation.ok()) {
      outcome.error =
          "closure of the seed clamped into the scale bounds failed: " + start_evaluation.error;
      return outcome;
    }
    record("clamped", 0, start_evaluation, start_evaluation.cost);
  }
  if ((options.prefit.enabled || options.segment_prefit.enabled) && seed_parameters.size() > 0)
    outcome.prefit_skipped = skip_reason;
  const int common_sims = commonStageMaxClosures(options.prefit, options.bounds);
  if (options.prefit.enabled && prefit_has_cords && seed_parameters.size() > 0 &&
      budget_allows(common_sims)) {
    PrefitOptions prefit = options.prefit;
    prefit.threads = options.finite_difference.threads;
    prefit.on_closure = stageHeartbeat(options.on_stage, "pre-fit");
    // The kind stage only when it fits as well (a small budget keeps the common factor).
    if (!budget_allows(common_sims + 2 * prefit.kind_points)) prefit.kind_points = 0;
    const PrefitResult result = globalScalePrefit(valve_case, start_set, start_evaluation,
                                                  options.bounds, seed_residual, prefit);
    outcome.forward_sims += result.forward_sims;
    outcome.prefit_ran = true;
    outcome.prefit_factor = result.factor;
    outcome.prefit_primary_factor = result.primary_factor;
    outcome.prefit_secondary_factor = result.secondary_factor;
    outcome.prefit_kind_stage = result.kind_stage;
    start_set = result.start;
    start_evaluation = result.best;
    record("prefit", 1, start_evaluation, start_evaluation.cost);
  }
  if (options.segment_prefit.enabled && prefit_has_cords && seed_parameters.size() > 0 &&
      options.mode != ParameterMode::kGroups && budget_allows(6 * options.segment_prefit.points)) {
    SegmentPrefitOptions segment = options.segment_prefit;
    segment.threads = options.finite_difference.threads;
    segment.on_closure = stageHeartbeat(options.on_stage, "segment pre-fit");
    const SegmentPrefitResult result = segmentScalePrefit(valve_case, start_set, start_evaluation,
                                                          options.bounds, seed_residual, segment);
    outcome.forward_sims += result.forward_sims;
    outcome.segment_prefit_ran = true;
    outcome.segment_prefit_changes = result.changed;
    segment_prefit_ids = result.changed_segments;
    start_set = result.start;
    start_evaluation = result.best;
    record("segments", 2, start_evaluation, start_evaluation.cost);
  }

  // Softer tissue per segment first when asked for (--tissue-prefit).
  if (options.tissue_prefit.enabled && seed_parameters.size() > 0 &&
      budget_allows(options.tissue_prefit.closures())) {
    TissuePrefitOptions tissue = options.tissue_prefit;
    tissue.threads = options.finite_difference.threads;
    tissue.on_closure = stageHeartbeat(options.on_stage, "tissue pre-fit");
    const TissuePrefitResult result = segmentTissuePrefit(valve_case, start_set, start_evaluation,
                                                          options.bounds, seed_residual, tissue);
    outcome.forward_sims += result.forward_sims;
    outcome.tissue_prefit_ran = true;
    outcome.tissue_prefit_changes = result.changed;
    outcome.tissue = result.tissue;
    start_set = result.start;
    start_evaluation = result.best;
    record("tissue", 3, start_evaluation, start_evaluation.cost);
  }

  // What an optimisation's result makes the outcome say.
  auto adopt = [&](const Optimisation& run) {
    outcome.termination = run.termination;
    outcome.budget_spent = run.budget_spent;
    outcome.switched_to_full_closures = run.switched_to_full_closures;
    outcome.slack_release = run.release;
    outcome.parameter_names = run.parameters->names();
    outcome.parameter_is_scale.clear();
    for (int p = 0; p < run.parameters->size(); ++p)
      outcome.parameter_is_scale.push_back(run.parameters->isScale(p));
    outcome.cord_parameter = run.parameters->cordParameter();
  };
  std::unique_ptr<Optimisation> run = optimise(
      valve_case, seed, settings, options,
      {start_set, start_evaluation, outcome.tissue, segment_prefit_ids, outcome.forward_sims},
      start);
  for (const IterationRecord& r : run->history) outcome.history.push_back(r);
  outcome.forward_sims = run->forward_sims;
  int optimiser_unsettled = run->residual->unsettledClosures();
  adopt(*run);
  if (!run->error.empty()) {
    outcome.error = run->error;
    outcome.error_is_input = run->error_is_input;
    return outcome;
  }

  // The tissue retry: a prolapse of the tracings the cords alone did not make.
  TissueRetry& retry = outcome.tissue_retry;
  retry.missing = prolapseMissingInClosure(valve_case, run->best->closed_V);
  if (!retry.missing.empty()) {
    retry.data_cost_without = run->dataCost();
    retry.mean_mm_without = run->best->mean_deviation_mm;
  }
  if (options.tissue_retry && !outcome.tissue_prefit_ran && !retry.missing.empty()) {
    // Softer tissue where the flap is missing, nowhere else: the tracings say where to look.
    TissuePrefitOptions tissue = options.tissue_prefit;
    tissue.enabled = true;
    tissue.threads = options.finite_difference.threads;
    tissue.segments = segmentIds(valve_case.mesh, retry.missing);
    tissue.on_closure = stageHeartbeat(options.on_stage, "retry tissue pre-fit");
    const int needed = tissue.closures(static_cast<int>(tissue.segments.size())) + 2;
    if (run->parameters->size() == 0) {
      retry.skipped = "no free cord";
    } else if (tissue.segments.empty()) {
      retry.skipped = "the mesh has no vertex in " + joinSegments(retry.missing);
    } else if (outcome.forward_sims + needed > options.max_sims) {
      retry.skipped = "--max-sims " + std::to_string(options.max_sims) + " leaves " +
                      std::to_string(std::max(0, options.max_sims - outcome.forward_sims)) +
                      " closures, it needs at least " + std::to_string(needed);
    } else {
      retry.ran = true;
      if (options.on_stage)
        options.on_stage("tissue retry: the tracings show prolapse in " +
                         joinSegments(retry.missing) +
                         ", the fit does not; softer tissue there, then the fit again from the "
                         "pre-fits, within the " +
                         std::to_string(options.max_sims - outcome.forward_sims) +
                         " closures left of --max-sims");
      // Its records carry "retry " before the stage and the best cost of the whole fit, so
      // that the progress lines and convergence.csv tell the two optimisations apart.
      const double best_before = run->best->cost;
      const auto relabel = [best_before](IterationRecord r) {
        r.stage = "retry " + r.stage;
        r.best_cost = std::min(r.best_cost, best_before);
        return r;
      };
      const int sims_before_retry = outcome.forward_sims;
      const TissuePrefitResult softened = segmentTissuePrefit(
          valve_case, start_set, start_evaluation, options.bounds, seed_residual, tissue);
      outcome.forward_sims += softened.forward_sims;
      retry.tissue_changes = softened.changed;
      const IterationRecord tissue_record = closureRecord(
          "tissue", 3, softened.best, softened.best.cost, outcome.forward_sims, start);
      outcome.history.push_back(relabel(tissue_record));
      if (options.on_iteration) options.on_iteration(relabel(tissue_record));
      if (!softened.changed.empty()) {
        FitOptions retry_options = options;
        if (options.on_iteration)
          retry_options.on_iteration = [on_iteration = options.on_iteration, relabel](
                                           const IterationRecord& r) { on_iteration(relabel(r)); };
        std::unique_ptr<Optimisation> second =
            optimise(valve_case, seed, settings, retry_options,
                     {softened.start, softened.best, softened.tissue, segment_prefit_ids,
                      outcome.forward_sims},
                     start);
        for (const IterationRecord& r : second->history) outcome.history.push_back(relabel(r));
        outcome.forward_sims = second->forward_sims;
        optimiser_unsettled += second->residual->unsettledClosures();
        if (!second->error.empty()) {
          retry.error = second->error;
        } else {
          retry.data_cost_with = second->dataCost();
          retry.mean_mm_with = second->best->mean_deviation_mm;
          retry.missing_after = prolapseMissingInClosure(valve_case, second->best->closed_V);
          retry.kept = retry.data_cost_with <
                       retry.data_cost_without * (1.0 - options.tissue_retry_min_gain);
          if (retry.kept) {
            // The first optimisation's stop stays on record (only the retry's was).
            const std::string first_termination = run->termination;
            run = std::move(second);
            adopt(*run);
            outcome.termination += "; before the tissue retry: " + first_termination;
            outcome.tissue = softened.tissue;
            outcome.tissue_prefit_changes = softened.changed;
          }
        }
      }
      retry.forward_sims = outcome.forward_sims - sims_before_retry;
    }
  }

  const Optimisation& fit = *run;
  const FitParameterization& parameters = *fit.parameters;
  const ForwardResidual& residual = *fit.residual;
  FitObjective& objective = *fit.objective;
  std::shared_ptr<const ForwardEvaluation> best = fit.best;
  outcome.x = best->x;
  outcome.final_evaluation = *best;
  outcome.fitted = parameters.apply(best->x);
  // Provenance against the seed as given: the pre-fit may have changed a cord the optimiser
  // left alone.
  for (std::size_t c = 0; c < outcome.fitted.cords.size(); ++c) {
    Cord& cord = outcome.fitted.cords[c];
    const Cord& original = seed.cords[c];
    if (cord.rest_length == original.rest_length) {
      cord.provenance = original.provenance;
    } else {
      cord.provenance = Provenance::kFitted;
    }
  }
  outcome.closed_spans = closedSpans(outcome.fitted, residual.cordInsertions(), best->closed_V);
  // The pre-fits' closures (the retry's tissue pre-fit too) count in the seed residual's.
  outcome.unsettled_sims = seed_residual.unsettledClosures() + optimiser_unsettled;
  outcome.seconds = seconds();
  // The diagnostics after the fit close through the same residual; their unsettled closures
  // are counted apart, as their closures are (outside --max-sims).
  const int unsettled_in_fit = residual.unsettledClosures();
  if (options.uncertainty && parameters.size() > 0) {
    // The optimiser's Jacobian also holds at the release when the release closed the valve
    // to the same state (its cords slack throughout): the data depend on x only through it.
    std::shared_ptr<const Eigen::MatrixXd> J = objective.cachedJacobian(fit.optimiser_best->x);
    if (best != fit.optimiser_best && best->closed_V != fit.optimiser_best->closed_V) J = nullptr;
    int jacobian_sims = 0;
    std::string jacobian_error;
    if (!J) {
      if (options.on_stage) {
        const std::vector<bool> slack =
            slackParameters(parameters, residual.cordInsertions(), best->x, best->closed_V,
                            objective.finiteDifferences());
        const auto moving = std::count(slack.begin(), slack.end(), false);
        options.on_stage("uncertainty: the Jacobian at the fit, " + std::to_string(2 * moving) +
                         " closures (2 for each of the " + std::to_string(moving) +
                         (objective.finiteDifferences().skip_slack
                              ? " parameters that move a taut cord)"
                              : " parameters)"));
      }
      // The objective's differences: full closures when the driver gave up warm-started ones.
      FiniteDifferenceOptions fd = objective.finiteDifferences();
      fd.on_closure = closureHeartbeat(options.on_stage, "uncertainty");
      JacobianResult result = centralDifferenceJacobian(residual, best->x, best->closed_V, fd);
      jacobian_sims = result.forward_sims;
      jacobian_error = result.error;
      if (result.ok()) J = std::make_shared<const Eigen::MatrixXd>(std::move(result.J));
    }
    if (J) {
      std::vector<int> runs;  // the stacked tracing points, polyline by polyline
      for (const Tracing& t : fit.working_case.tracings)
        runs.push_back(static_cast<int>(t.points.rows()));
      outcome.uncertainty = fitUncertainty(*J, best->data, runs, options.residual.huber_delta_mm,
                                           residual.regularisationJacobian(), best->x,
                                           parameters.lower(), parameters.upper());
    } else {
      outcome.uncertainty.error =
          "uncertainty: a finite-difference closure failed: " + jacobian_error;
    }
    outcome.uncertainty.jacobian_sims = jacobian_sims;
    outcome.uncertainty.unsettled_sims = residual.unsettledClosures() - unsettled_in_fit;
    outcome.uncertainty_seconds = seconds() - outcome.seconds;
  }
  if (options.probe_locked) {
    LockedCordProbeOptions probe;
    probe.relative_step = options.finite_difference.scale_step;
    probe.threads = options.finite_difference.threads;
    probe.on_start = options.on_stage;
    probe.on_closure = stageHeartbeat(options.on_stage, "locked-cord probe");
    outcome.locked_probes = probeLockedCords(fit.working_case, outcome.fitted, *best,
                                             outcome.closed_spans, residual, options.bounds, probe);
    outcome.locked_probes.unsettled_sims =
        residual.unsettledClosures() - unsettled_in_fit - outcome.uncertainty.unsettled_sims;
  }
  return outcome;
}

}  // namespace chordfit::inverse
