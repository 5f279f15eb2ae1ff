// One optimisation of a case's cords from a start (the fit, inverse/fit_cords.cpp, runs one,
// and a second in the tissue retry): the chosen optimiser on the chosen parameterisation, then the
// slack release (slack_release.h). Internal to the fit; `chordfit fit` and the tests call fitCords.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"
#include "core/cordset.h"
#include "core/simulator.h"
#include "inverse/fit_objective.h"
#include "inverse/fit_parameters.h"
#include "inverse/forward_residual.h"
#include "inverse/slack_release.h"

namespace chordfit::inverse {

struct FitOptions;

// What one optimisation leaves. Heap-held and never moved: the parameterisation, residual and
// objective refer to working_case and to each other.
struct Optimisation {
  Optimisation() = default;
  Optimisation(const Optimisation&) = delete;  // a copy's members would refer to this one's
  Optimisation& operator=(const Optimisation&) = delete;

  ValveCase working_case;  // the case, on the start's tissue
  std::unique_ptr<FitParameterization> parameters;
  std::unique_ptr<ForwardResidual> residual;
  std::unique_ptr<FitObjective> objective;
  // best: after the slack release (the optimiser's own best when the release was not kept).
  std::shared_ptr<const ForwardEvaluation> best, optimiser_best;
  std::string termination;
  bool budget_spent = false;  // the optimiser stopped for the budget
  bool switched_to_full_closures = false;
  SlackReleaseOutcome release;
  std::vector<IterationRecord> history;
  int forward_sims = 0;  // cumulative, every stage of the fit so far
  std::string error;     // set: best and optimiser_best may be unset
  bool error_is_input = false;

  // The best closure's cost without the priors: what the tissue retry compares.
  double dataCost() const {
    return residual->cost(best->data, Eigen::VectorXd::Zero(best->regularisation.size()));
  }
};

// Where an optimisation starts: the pre-fits' result.
struct OptimisationStart {
  const CordSet& cords;                       // after the pre-fits
  const ForwardEvaluation& evaluation;        // its full closure on `tissue`
  const Eigen::VectorXd& tissue;              // per-vertex factors; empty: the case's own
  const std::vector<int>& rescaled_segments;  // by the segment pre-fit
  int sims_before = 0;                        // closures the fit ran before this one
};

// Optimises the cords of `from.cords` (seed: the cord set as the user gave it, the slack
// release's reference) within options.max_sims in all, then releases slack cords when the
// budget leaves a closure for it. Records go to the result's history and, as they happen, to
// options.on_iteration; elapsed times count from clock_start. Never throws for a failed
// closure: the result's error says what failed.
std::unique_ptr<Optimisation> optimise(const ValveCase& valve_case, const CordSet& seed,
                                       const SimulationSettings& settings,
                                       const FitOptions& options, const OptimisationStart& from,
                                       FitObjective::Clock::time_point clock_start);

// The history record of a closure run outside the optimiser's iterations (seed, pre-fits,
// slack release, the retry's tissue pre-fit). A failed closure has no cost or deviation: NaN
// in the history (docs/outputs.md).
IterationRecord closureRecord(const std::string& stage, int iteration, const ForwardEvaluation& e,
                              double best_cost, int forward_sims,
                              FitObjective::Clock::time_point clock_start);

}  // namespace chordfit::inverse
