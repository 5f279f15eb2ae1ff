#include "inverse/fit_cords.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <utility>

#include "core/carpentier.h"
#include "core/metrics.h"
#include "inverse/cord_optimisation.h"

namespace chordfit::inverse {

namespace {

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

// Why `options` cannot make a fit, or "".
std::string optionsProblem(const FitOptions& options) {
  if (!makeOptimizer(options.optimizer)) return "unknown optimizer \"" + options.optimizer + "\"";
  if (!(options.bounds.scale_lower > 0.0 &&
        options.bounds.scale_lower < options.bounds.scale_upper))
    return "scale bounds: need 0 < lower < upper";
  return "";
}

// The stages of one fit, in the order fitCords runs them; each adds to the outcome. Refers to
// the caller's inputs, which outlive it; not copied (the seed residual refers to the seed
// parameterisation).
class CordFit {
 public:
  using Clock = FitObjective::Clock;

  CordFit(const ValveCase& valve_case, const CordSet& seed, const SimulationSettings& settings,
          const FitOptions& options, Clock::time_point start)
      : valve_case_(valve_case),
        seed_(seed),
        settings_(settings),
        options_(options),
        start_(start),
        seed_parameters_(valve_case, seed, options.mode, options.bounds),
        seed_residual_(valve_case, seed_parameters_, settings, options.residual) {
    outcome_.seed = seed;
  }
  CordFit(const CordFit&) = delete;
  CordFit& operator=(const CordFit&) = delete;

  // Seed closure (full, from the open state): the "before" of every report, of the seed as
  // given. A seed outside the bounds (a manual cord edited past them) is closed as it is here;
  // the optimiser then starts from it clamped into the bounds, and closes that itself.
  // False when the closure failed (the outcome's error says why).
  bool closeSeed() {
    outcome_.seed_evaluation = seed_parameters_.startClamped()
                                   ? closeForData(valve_case_, seed_, seed_residual_)
                                   : seed_residual_.evaluate(seed_parameters_.initial());
    outcome_.forward_sims = 1;
    if (!outcome_.seed_evaluation.ok()) {
      outcome_.error = "seed closure failed: " + outcome_.seed_evaluation.error;
      return false;
    }
    record("seed", 0, outcome_.seed_evaluation, outcome_.seed_evaluation.cost);
    start_set_ = seed_;
    start_evaluation_ = outcome_.seed_evaluation;
    return true;
  }

  // The pre-fits that pick the optimiser's start: global and per kind, per segment, and
  // softer tissue per segment when asked for (--tissue-prefit). Each runs only when its
  // closures fit in the budget, leaving the optimiser one. False when a closure failed.
  bool runPrefits() {
    const std::string skip_reason = prefitSkipReason(seed_);
    const bool has_cords = skip_reason.empty() && seed_parameters_.size() > 0;
    if (!clampStartIntoBounds(skip_reason.empty())) return false;
    if ((options_.prefit.enabled || options_.segment_prefit.enabled) && seed_parameters_.size() > 0)
      outcome_.prefit_skipped = skip_reason;
    if (options_.prefit.enabled && has_cords &&
        budgetAllows(commonStageMaxClosures(options_.prefit, options_.bounds)))
      runGlobalPrefit();
    if (options_.segment_prefit.enabled && has_cords && options_.mode != ParameterMode::kGroups &&
        budgetAllows(6 * options_.segment_prefit.points))
      runSegmentPrefit();
    if (options_.tissue_prefit.enabled && seed_parameters_.size() > 0 &&
        budgetAllows(options_.tissue_prefit.closures()))
      runTissuePrefit();
    return true;
  }

  // The optimiser from the pre-fits' start, then the slack release. False when it failed.
  bool runOptimiser() {
    run_ = optimise(valve_case_, seed_, settings_, options_,
                    {start_set_, start_evaluation_, outcome_.tissue, segment_prefit_ids_,
                     outcome_.forward_sims},
                    start_);
    for (const IterationRecord& r : run_->history) outcome_.history.push_back(r);
    outcome_.forward_sims = run_->forward_sims;
    optimiser_unsettled_ = run_->residual->unsettledClosures();
    adopt(*run_);
    if (run_->error.empty()) return true;
    outcome_.error = run_->error;
    outcome_.error_is_input = run_->error_is_input;
    return false;
  }

  // The tissue retry: a prolapse of the tracings the cords alone did not make. Softer tissue
  // where the flap is missing, nowhere else (the tracings say where to look), then the
  // optimiser again; kept when it fits the tracings better by tissue_retry_min_gain.
  void retryOnSofterTissue() {
    TissueRetry& retry = outcome_.tissue_retry;
    retry.missing = prolapseMissingInClosure(valve_case_, run_->best->closed_V);
    if (retry.missing.empty()) return;
    retry.data_cost_without = run_->dataCost();
    retry.mean_mm_without = run_->best->mean_deviation_mm;
    if (!options_.tissue_retry || outcome_.tissue_prefit_ran) return;
    TissuePrefitOptions tissue = options_.tissue_prefit;
    tissue.enabled = true;
    tissue.threads = options_.finite_difference.threads;
    tissue.segments = segmentIds(valve_case_.mesh, retry.missing);
    tissue.on_closure = stageHeartbeat(options_.on_stage, "retry tissue pre-fit");
    retry.skipped = retrySkipReason(tissue);
    if (retry.skipped.empty()) runTissueRetry(tissue);
  }

  // The fitted cord set and what is known of it without further closures.
  void adoptFittedCords() {
    const ForwardEvaluation& best = *run_->best;
    outcome_.x = best.x;
    outcome_.final_evaluation = best;
    outcome_.fitted = run_->parameters->apply(best.x);
    // Provenance against the seed as given: the pre-fit may have changed a cord the optimiser
    // left alone.
    for (std::size_t c = 0; c < outcome_.fitted.cords.size(); ++c) {
      Cord& cord = outcome_.fitted.cords[c];
      const Cord& original = seed_.cords[c];
      cord.provenance =
          cord.rest_length == original.rest_length ? original.provenance : Provenance::kFitted;
    }
    outcome_.closed_spans =
        closedSpans(outcome_.fitted, run_->residual->cordInsertions(), best.closed_V);
    // The pre-fits' closures (the retry's tissue pre-fit too) count in the seed residual's.
    outcome_.unsettled_sims = seed_residual_.unsettledClosures() + optimiser_unsettled_;
    outcome_.seconds = seconds();
    // The diagnostics after the fit close through the same residual; their unsettled closures
    // are counted apart, as their closures are (outside --max-sims).
    unsettled_in_fit_ = run_->residual->unsettledClosures();
  }

  // Each parameter's SD and data sensitivity at the fit (fit_uncertainty.h), from the
  // optimiser's last Jacobian where it still holds, else from a new one (outside --max-sims).
  void estimateUncertainty() {
    const Optimisation& fit = *run_;
    if (fit.parameters->size() == 0) return;
    const ForwardResidual& residual = *fit.residual;
    const ForwardEvaluation& best = *fit.best;
    // The optimiser's Jacobian also holds at the release when the release closed the valve
    // to the same state (its cords slack throughout): the data depend on x only through it.
    std::shared_ptr<const Eigen::MatrixXd> J = fit.objective->cachedJacobian(fit.optimiser_best->x);
    if (fit.best != fit.optimiser_best && best.closed_V != fit.optimiser_best->closed_V)
      J = nullptr;
    int jacobian_sims = 0;
    std::string jacobian_error;
    if (!J) {
      JacobianResult result = jacobianAtFit();
      jacobian_sims = result.forward_sims;
      jacobian_error = result.error;
      if (result.ok()) J = std::make_shared<const Eigen::MatrixXd>(std::move(result.J));
    }
    FitUncertainty& uncertainty = outcome_.uncertainty;
    if (J) {
      std::vector<int> runs;  // the stacked tracing points, polyline by polyline
      for (const Tracing& t : fit.working_case.tracings)
        runs.push_back(static_cast<int>(t.points.rows()));
      uncertainty = fitUncertainty(*J, best.data, runs, options_.residual.huber_delta_mm,
                                   residual.regularisationJacobian(), best.x,
                                   fit.parameters->lower(), fit.parameters->upper());
    } else {
      uncertainty.error = "uncertainty: a finite-difference closure failed: " + jacobian_error;
    }
    uncertainty.jacobian_sims = jacobian_sims;
    uncertainty.unsettled_sims = residual.unsettledClosures() - unsettled_in_fit_;
    outcome_.uncertainty_seconds = seconds() - outcome_.seconds;
  }

  // Whether a lock holds the fit back: each taut locked cord let go (locked_cord_probe.h).
  void probeLocks() {
    const ForwardResidual& residual = *run_->residual;
    LockedCordProbeOptions probe;
    probe.relative_step = options_.finite_difference.scale_step;
    probe.threads = options_.finite_difference.threads;
    probe.on_start = options_.on_stage;
    probe.on_closure = stageHeartbeat(options_.on_stage, "locked-cord probe");
    outcome_.locked_probes =
        inverse::probeLockedCords(run_->working_case, outcome_.fitted, *run_->best,
                                  outcome_.closed_spans, residual, options_.bounds, probe);
    outcome_.locked_probes.unsettled_sims =
        residual.unsettledClosures() - unsettled_in_fit_ - outcome_.uncertainty.unsettled_sims;
  }

  // What the stages run so far found (the whole fit once they all ran).
  FitOutcome& outcome() { return outcome_; }

 private:
  double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  // Records a closure run outside the optimiser in the history and reports it.
  void record(const std::string& stage, int iteration, const ForwardEvaluation& e,
              double best_cost) {
    const IterationRecord r =
        closureRecord(stage, iteration, e, best_cost, outcome_.forward_sims, start_);
    outcome_.history.push_back(r);
    if (options_.on_iteration) options_.on_iteration(r);
  }

  // Whether `sims` more closures leave the budget one for the optimiser.
  bool budgetAllows(int sims) const {
    return outcome_.forward_sims + sims + 1 <= options_.max_sims;
  }

  // A seed outside the bounds (a manual cord edited past them): the pre-fits start where the
  // optimiser would, from the seed clamped into the bounds. They started from the seed as
  // given: a cord at 0.06 of its length ran every pre-fit closure to the step cap, and the
  // factors were fitted to a valve the optimiser never started from. Only when a pre-fit
  // stage will run: else the optimiser closes the clamped start itself. False when the
  // clamped closure failed.
  bool clampStartIntoBounds(bool prefit_has_cords) {
    const bool cord_prefit_runs =
        prefit_has_cords && (options_.prefit.enabled || (options_.segment_prefit.enabled &&
                                                         options_.mode != ParameterMode::kGroups));
    const bool any_prefit =
        (cord_prefit_runs || options_.tissue_prefit.enabled) && seed_parameters_.size() > 0;
    if (!(seed_parameters_.startClamped() && any_prefit && budgetAllows(1))) return true;
    start_set_ = seed_parameters_.apply(seed_parameters_.initial());
    start_evaluation_ = seed_residual_.evaluate(seed_parameters_.initial());
    ++outcome_.forward_sims;
    if (!start_evaluation_.ok()) {
      outcome_.error =
          "closure of the seed clamped into the scale bounds failed: " + start_evaluation_.error;
      return false;
    }
    record("clamped", 0, start_evaluation_, start_evaluation_.cost);
    return true;
  }

  // A pre-fit stage's result (global_prefit.h, segment_prefit.h, tissue_prefit.h) becomes the
  // optimiser's start, recorded as history entry `iteration` of `stage`.
  template <typename StageResult>
  void startFrom(const StageResult& result, const char* stage, int iteration) {
    outcome_.forward_sims += result.forward_sims;
    start_set_ = result.start;
    start_evaluation_ = result.best;
    record(stage, iteration, start_evaluation_, start_evaluation_.cost);
  }

  // The global pre-fit (global_prefit.h): one factor on every free non-manual cord, then one
  // per kind when the budget leaves room for it.
  void runGlobalPrefit() {
    PrefitOptions prefit = options_.prefit;
    prefit.threads = options_.finite_difference.threads;
    prefit.on_closure = stageHeartbeat(options_.on_stage, "pre-fit");
    // The kind stage only when it fits as well (a small budget keeps the common factor).
    if (!budgetAllows(commonStageMaxClosures(options_.prefit, options_.bounds) +
                      2 * prefit.kind_points))
      prefit.kind_points = 0;
    const PrefitResult result = globalScalePrefit(valve_case_, start_set_, start_evaluation_,
                                                  options_.bounds, seed_residual_, prefit);
    outcome_.prefit_ran = true;
    outcome_.prefit_factor = result.factor;
    outcome_.prefit_primary_factor = result.primary_factor;
    outcome_.prefit_secondary_factor = result.secondary_factor;
    outcome_.prefit_kind_stage = result.kind_stage;
    startFrom(result, "prefit", 1);
  }

  // The segment pre-fit (segment_prefit.h): a factor per Carpentier segment.
  void runSegmentPrefit() {
    SegmentPrefitOptions segment = options_.segment_prefit;
    segment.threads = options_.finite_difference.threads;
    segment.on_closure = stageHeartbeat(options_.on_stage, "segment pre-fit");
    const SegmentPrefitResult result = segmentScalePrefit(
        valve_case_, start_set_, start_evaluation_, options_.bounds, seed_residual_, segment);
    outcome_.segment_prefit_ran = true;
    outcome_.segment_prefit_changes = result.changed;
    segment_prefit_ids_ = result.changed_segments;
    startFrom(result, "segments", 2);
  }

  // The tissue pre-fit (tissue_prefit.h, --tissue-prefit): softer tissue per segment.
  void runTissuePrefit() {
    TissuePrefitOptions tissue = options_.tissue_prefit;
    tissue.threads = options_.finite_difference.threads;
    tissue.on_closure = stageHeartbeat(options_.on_stage, "tissue pre-fit");
    const TissuePrefitResult result = segmentTissuePrefit(
        valve_case_, start_set_, start_evaluation_, options_.bounds, seed_residual_, tissue);
    outcome_.tissue_prefit_ran = true;
    outcome_.tissue_prefit_changes = result.changed;
    outcome_.tissue = result.tissue;
    startFrom(result, "tissue", 3);
  }

  // What an optimisation's result makes the outcome say.
  void adopt(const Optimisation& run) {
    outcome_.termination = run.termination;
    outcome_.budget_spent = run.budget_spent;
    outcome_.switched_to_full_closures = run.switched_to_full_closures;
    outcome_.slack_release = run.release;
    outcome_.parameter_names = run.parameters->names();
    outcome_.parameter_is_scale.clear();
    for (int p = 0; p < run.parameters->size(); ++p)
      outcome_.parameter_is_scale.push_back(run.parameters->isScale(p));
    outcome_.cord_parameter = run.parameters->cordParameter();
  }

  // Why the tissue retry cannot run with `tissue`, or "".
  std::string retrySkipReason(const TissuePrefitOptions& tissue) const {
    const int needed = tissue.closures(static_cast<int>(tissue.segments.size())) + 2;
    if (run_->parameters->size() == 0) return "no free cord";
    if (tissue.segments.empty())
      return "the mesh has no vertex in " + joinSegments(outcome_.tissue_retry.missing);
    if (outcome_.forward_sims + needed > options_.max_sims)
      return "--max-sims " + std::to_string(options_.max_sims) + " leaves " +
             std::to_string(std::max(0, options_.max_sims - outcome_.forward_sims)) +
             " closures, it needs at least " + std::to_string(needed);
    return "";
  }

  // The retry itself: the tissue pre-fit in the missing segments, from the pre-fits' start,
  // then a second optimisation when it softened any; that one replaces the first when kept.
  void runTissueRetry(const TissuePrefitOptions& tissue) {
    TissueRetry& retry = outcome_.tissue_retry;
    retry.ran = true;
    if (options_.on_stage)
      options_.on_stage("tissue retry: the tracings show prolapse in " +
                        joinSegments(retry.missing) +
                        ", the fit does not; softer tissue there, then the fit again from the "
                        "pre-fits, within the " +
                        std::to_string(options_.max_sims - outcome_.forward_sims) +
                        " closures left of --max-sims");
    // Its records carry "retry " before the stage and the best cost of the whole fit, so
    // that the progress lines and convergence.csv tell the two optimisations apart.
    const double best_before = run_->best->cost;
    const auto relabel = [best_before](IterationRecord r) {
      r.stage = "retry " + r.stage;
      r.best_cost = std::min(r.best_cost, best_before);
      return r;
    };
    const int sims_before_retry = outcome_.forward_sims;
    const TissuePrefitResult softened = segmentTissuePrefit(
        valve_case_, start_set_, start_evaluation_, options_.bounds, seed_residual_, tissue);
    outcome_.forward_sims += softened.forward_sims;
    retry.tissue_changes = softened.changed;
    const IterationRecord tissue_record = closureRecord(
        "tissue", 3, softened.best, softened.best.cost, outcome_.forward_sims, start_);
    outcome_.history.push_back(relabel(tissue_record));
    if (options_.on_iteration) options_.on_iteration(relabel(tissue_record));
    if (!softened.changed.empty()) {
      FitOptions retry_options = options_;
      if (options_.on_iteration)
        retry_options.on_iteration = [on_iteration = options_.on_iteration, relabel](
                                         const IterationRecord& r) { on_iteration(relabel(r)); };
      std::unique_ptr<Optimisation> second =
          optimise(valve_case_, seed_, settings_, retry_options,
                   {softened.start, softened.best, softened.tissue, segment_prefit_ids_,
                    outcome_.forward_sims},
                   start_);
      for (const IterationRecord& r : second->history) outcome_.history.push_back(relabel(r));
      outcome_.forward_sims = second->forward_sims;
      optimiser_unsettled_ += second->residual->unsettledClosures();
      if (!second->error.empty()) {
        retry.error = second->error;
      } else {
        retry.data_cost_with = second->dataCost();
        retry.mean_mm_with = second->best->mean_deviation_mm;
        retry.missing_after = prolapseMissingInClosure(valve_case_, second->best->closed_V);
        retry.kept =
            retry.data_cost_with < retry.data_cost_without * (1.0 - options_.tissue_retry_min_gain);
        if (retry.kept) {
          // The first optimisation's stop stays on record (only the retry's was).
          const std::string first_termination = run_->termination;
          run_ = std::move(second);
          adopt(*run_);
          outcome_.termination += "; before the tissue retry: " + first_termination;
          outcome_.tissue = softened.tissue;
          outcome_.tissue_prefit_changes = softened.changed;
        }
      }
    }
    retry.forward_sims = outcome_.forward_sims - sims_before_retry;
  }

  // A new Jacobian at the fit for the uncertainty: the objective's differences (full closures
  // when the driver gave up warm-started ones).
  JacobianResult jacobianAtFit() const {
    const Optimisation& fit = *run_;
    const ForwardEvaluation& best = *fit.best;
    const FiniteDifferenceOptions& objective_fd = fit.objective->finiteDifferences();
    if (options_.on_stage) {
      const std::vector<bool> slack = slackParameters(
          *fit.parameters, fit.residual->cordInsertions(), best.x, best.closed_V, objective_fd);
      const auto moving = std::count(slack.begin(), slack.end(), false);
      options_.on_stage(
          "uncertainty: the Jacobian at the fit, " + std::to_string(2 * moving) +
          " closures (2 for each of the " + std::to_string(moving) +
          (objective_fd.skip_slack ? " parameters that move a taut cord)" : " parameters)"));
    }
    FiniteDifferenceOptions fd = objective_fd;
    fd.on_closure = closureHeartbeat(options_.on_stage, "uncertainty");
    return centralDifferenceJacobian(*fit.residual, best.x, best.closed_V, fd);
  }

  const ValveCase& valve_case_;
  const CordSet& seed_;
  const SimulationSettings& settings_;
  const FitOptions& options_;
  const Clock::time_point start_;
  const FitParameterization seed_parameters_;
  const ForwardResidual seed_residual_;  // the seed's and every pre-fit's closures
  FitOutcome outcome_;
  CordSet start_set_;  // the optimiser's start: the seed, then each pre-fit's result
  ForwardEvaluation start_evaluation_;
  std::vector<int> segment_prefit_ids_;  // segments the segment pre-fit rescaled
  std::unique_ptr<Optimisation> run_;    // the optimisation the fit keeps
  int optimiser_unsettled_ = 0;          // unsettled closures of the optimisations
  int unsettled_in_fit_ = 0;             // the kept residual's, before the diagnostics
};

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
  const FitObjective::Clock::time_point start = FitObjective::Clock::now();
  if (const std::string problem = optionsProblem(options); !problem.empty()) {
    FitOutcome outcome;
    outcome.seed = seed;
    outcome.error = problem;
    outcome.error_is_input = true;
    return outcome;
  }
  CordFit fit(valve_case, seed, settings, options, start);
  if (!fit.closeSeed() || !fit.runPrefits() || !fit.runOptimiser()) return std::move(fit.outcome());
  fit.retryOnSofterTissue();
  fit.adoptFittedCords();
  if (options.uncertainty) fit.estimateUncertainty();
  if (options.probe_locked) fit.probeLocks();
  return std::move(fit.outcome());
}

}  // namespace chordfit::inverse
