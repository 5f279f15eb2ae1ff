// A whole fit of a case's cords (DESIGN §7, issue 5), in stages: the seed's closure; the
// pre-fits that pick the start (global and per kind, global_prefit.h; per segment,
// segment_prefit.h; softer tissue per segment when asked, tissue_prefit.h); the chosen
// optimiser on the chosen parameterisation, then the slack release (cord_optimisation.h);
// the tissue retry where the fit misses a prolapse the tracings show; then, outside the
// budget, each parameter's uncertainty (fit_uncertainty.h) and the locked-cord probe
// (locked_cord_probe.h). This is what `chordfit fit` and the tests call.
//
// Manual edits: locked cords are constants (bit for bit); unlocked manual cords are the start
// and the prior of their parameters and are not touched by the pre-fit.
// Reporting: every value reported (the seed's and the fit's cost, mean deviation, closed mesh)
// comes from a full closure from the open state.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/case_data.h"
#include "core/cordset.h"
#include "core/simulator.h"
#include "inverse/finite_difference.h"
#include "inverse/fit_objective.h"
#include "inverse/fit_parameters.h"
#include "inverse/fit_uncertainty.h"
#include "inverse/forward_residual.h"
#include "inverse/global_prefit.h"
#include "inverse/locked_cord_probe.h"
#include "inverse/optimizer.h"
#include "inverse/segment_prefit.h"
#include "inverse/slack_release.h"
#include "inverse/tissue_prefit.h"

namespace chordfit::inverse {

struct FitOptions {
  ParameterMode mode = ParameterMode::kScales;
  ParameterBounds bounds;
  ResidualOptions residual;
  FiniteDifferenceOptions finite_difference;  // .threads also used by the pre-fit
  PrefitOptions prefit;
  SegmentPrefitOptions segment_prefit;  // runs after the global pre-fit
  TissuePrefitOptions tissue_prefit;    // opt-in; runs after the segment pre-fit (and in the
                                        // tissue retry, with its factors and rounds)
  // After the optimiser, per-cord modes only (slack_release.h); one closure of the budget is
  // kept back for it.
  SlackReleaseOptions slack_release;
  std::string optimizer = "ceres";
  OptimizerSettings optimizer_settings;
  // Forward closures of the fit: the seed's, the pre-fits', the optimiser's, the slack
  // release's and the tissue retry's (FitOutcome::forward_sims). Not in it: the uncertainty's
  // and the locked-cord probe's (below), nor the closure `chordfit fit` writes out afterwards.
  int max_sims = 400;
  // After the fit, the uncertainty of each parameter (fit_uncertainty.h) from the Jacobian at
  // the best point: the optimiser's when it computed one there, else 2 closures per parameter
  // outside max_sims (FitOutcome::uncertainty.jacobian_sims). `chordfit fit` turns it on.
  bool uncertainty = false;
  // When the fitted closure misses a prolapse the tracings show (their segments not in its
  // sections), the tissue pre-fit tries softer tissue in those segments from the pre-fits'
  // start and, when it softens one, the optimisation runs once more on that tissue, within
  // what is left of max_sims; its result is kept if its data cost is lower by more than
  // tissue_retry_min_gain (relative). Not when the tissue pre-fit ran already. `chordfit fit`
  // turns it on (--no-tissue-retry turns it off).
  bool tissue_retry = false;
  double tissue_retry_min_gain = 0.01;
  // After the fit, a probe of each taut locked cord (locked_cord_probe.h): 3 closures each,
  // outside max_sims (FitOutcome::locked_probes). `chordfit fit` turns it on.
  bool probe_locked = false;
  std::function<void(const IterationRecord&)> on_iteration;  // progress (optional)
  // A line before each after-fit stage that runs closures (the uncertainty's Jacobian, the
  // locked-cord probe): what it is and how many closures (at most, for the probe) (optional).
  std::function<void(const std::string&)> on_stage;
};

// The tissue retry (FitOptions::tissue_retry): a prolapse the cords alone did not make.
struct TissueRetry {
  // The tracings' prolapse segments the first optimisation's sections lack (always computed,
  // also when the retry is off).
  std::vector<std::string> missing;
  bool ran = false;     // enabled, missing non-empty, the budget allowed it
  std::string skipped;  // why it did not run although enabled and segments were missing
  bool kept = false;    // the second optimisation is the fit's result
  // Its tissue pre-fit's changes, "P3 0.3, cords 1.5"; empty: nothing softer fitted better,
  // and no second optimisation ran.
  std::vector<std::string> tissue_changes;
  // Data costs and mean deviations of the two optimisations' results (full closures): the
  // first's whenever `missing` is non-empty, the second's when it ran without error.
  double data_cost_without = 0.0, data_cost_with = 0.0;
  double mean_mm_without = 0.0, mean_mm_with = 0.0;
  std::vector<std::string> missing_after;  // of the second optimisation's result
  int forward_sims = 0;                    // its closures (in FitOutcome::forward_sims)
  std::string error;                       // the second optimisation failed (then not kept)
};

// Why the cord pre-fits (global and segment) have nothing to do on `seed`, or "": they
// rescale only free cords without a manual value.
std::string prefitSkipReason(const CordSet& seed);

struct FitOutcome {
  std::string error;  // bad options or a failed seed closure; the rest is then unset
  CordSet seed;       // as given
  CordSet fitted;     // provenance kFitted where the rest length differs from the seed
  ForwardEvaluation seed_evaluation;   // full closure of the seed as given (even out of bounds)
  ForwardEvaluation final_evaluation;  // full closure of the fitted set
  // Each fitted cord's span there (closedSpans, cord_insertion.h): below its rest length by
  // more than kSlackMarginMm = slack.
  Eigen::VectorXd closed_spans;
  // Why the global and segment pre-fits did not run although enabled ("" when they ran or
  // were disabled): e.g. every free cord is manual, so no factor would change a cord.
  std::string prefit_skipped;
  bool prefit_ran = false, segment_prefit_ran = false;  // false also when the budget was short
  bool tissue_prefit_ran = false;  // --tissue-prefit ran (enabled and within the budget); the
                                   // tissue retry's run is in tissue_retry
  double prefit_factor = 1.0;      // common factor of the global pre-fit, then per kind:
  double prefit_primary_factor = 1.0, prefit_secondary_factor = 1.0;
  KindStage prefit_kind_stage = KindStage::kNotAsked;  // the global pre-fit's kind stage
  std::vector<std::string> segment_prefit_changes;     // "P2 1.3", per accepted segment
  std::vector<std::string> tissue_prefit_changes;      // "A2 0.1", per accepted segment
  // The slack release (slack_release.h): what it proposed, and whether its closure was kept
  // (then `fitted` has it).
  SlackReleaseOutcome slack_release;
  // Per-vertex tissue the cords were fitted on (tissue pre-fit); empty = the case's own.
  Eigen::VectorXd tissue;
  std::vector<std::string> parameter_names;
  std::vector<bool> parameter_is_scale;  // scale or group factor; false: tip offset (mm)
  std::vector<int> cord_parameter;       // per cord, its parameter (-1: locked)
  Eigen::VectorXd x;                     // fitted parameters
  std::vector<IterationRecord> history;  // seed, pre-fit and optimiser records
  int forward_sims = 0;
  int unsettled_sims = 0;      // of forward_sims: closures that reached their step cap
  double seconds = 0.0;        // the fit, without the uncertainty
  FitUncertainty uncertainty;  // empty (sd.size() == 0) when not asked for
  double uncertainty_seconds = 0.0;
  LockedCordProbes locked_probes;  // empty when not asked for or nothing is locked
  TissueRetry tissue_retry;        // when asked for
  std::string termination;
  bool budget_spent = false;  // the optimiser stopped for the --max-sims budget
  // Warm-started differences were given up for full closures during the solve (the Ceres
  // driver after rejected steps); the uncertainty then uses full closures too.
  bool switched_to_full_closures = false;
  bool error_is_input = false;  // the error is about the options (e.g. too small a budget)
  bool ok() const { return error.empty(); }
};

FitOutcome fitCords(const ValveCase& valve_case, const CordSet& seed,
                    const SimulationSettings& settings, const FitOptions& options);

}  // namespace chordfit::inverse
