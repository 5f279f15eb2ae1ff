// Global scale pre-fit: one common factor on the rest lengths of every free, non-manual cord,
// chosen on a grid before the per-cord (or group) optimisation.
//
// Why: a cord that is slack in the closed state has an exactly zero data gradient, so a
// gradient method started where most cords are slack cannot move them. The paper's heuristic
// rest length is an upper bound (docs/fitting.md): from the heuristic seed most cords are
// slack and the valve prolapses everywhere. The paper's user first scales all cords; so does
// this stage, derivative-free: a grid of `points` factors over the scale bounds, then
// `refine_points` between the best grid point's neighbours. The closures are independent and
// run on `threads` threads (results per slot: independent of the thread count). The choice is
// by the data cost 1/2 sum rho(r^2) alone.
//
// Then per cord kind (secondaries first, then primaries), `kind_points` factors for that
// kind's cords alone around the common one (steps of half a grid spacing). Why: the two kinds
// hold different parts of the leaflet (free edge, belly), and one common factor is a
// compromise between them: on the prolapse-P2 cohort case the best common factor leaves the
// belly high and the free edge low (docs/fitting.md, "Pre-fit stages: what was tried").
// Manual (provenance manual) and locked cords keep their values: the user's edits are the
// starting point and prior of the optimisation, not something to rescale.
#pragma once

#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "core/case_data.h"
#include "core/cordset.h"
#include "core/simulator.h"
#include "inverse/fit_objective.h"
#include "inverse/fit_parameters.h"
#include "inverse/forward_residual.h"

namespace chordfit::inverse {

struct PrefitOptions {
  bool enabled = true;
  int points = 9;         // grid over [scale_lower, scale_upper], ends included
  int refine_points = 4;  // then evenly inside the best point's two grid intervals
  int kind_points = 4;    // then per cord kind around the common factor (0: no kind stage)
  int threads = 2;
  // Progress of the stage's closures (FiniteDifferenceOptions::on_closure); optional.
  std::function<void(int, int)> on_closure;
};

// Whether the kind stage ran: not asked for (kind_points 0, e.g. a budget too small for it),
// or only one cord kind free (the other all manual or locked), so no factor per kind.
enum class KindStage { kNotAsked, kOneKindFree, kRan };

struct PrefitResult {
  double factor = 1.0;  // best common factor (1: no change)
  // Per kind after the kind stage (= factor when the kind stage kept the common one).
  double primary_factor = 1.0, secondary_factor = 1.0;
  KindStage kind_stage = KindStage::kNotAsked;
  CordSet start;           // the seed with the factors applied
  ForwardEvaluation best;  // full closure at the best factor
  int forward_sims = 0;
  std::vector<double> factors, costs;  // every factor tried, in order, and its data cost
  std::string error;
};

// The most closures the common stage (grid and refinement) runs; the kind stage adds at most
// 2 * kind_points.
int commonStageMaxClosures(const PrefitOptions& options, const ParameterBounds& bounds);

// seed_evaluation: the seed's closure (factor 1), already run; it is not run again.
PrefitResult globalScalePrefit(const ValveCase& valve_case, const CordSet& seed,
                               const ForwardEvaluation& seed_evaluation,
                               const ParameterBounds& bounds, const ForwardResidual& residual,
                               const PrefitOptions& options);

// One full closure of `cords` on `valve_case` (its tissue included) from the open state: data
// residuals and the data-only cost; error set when the closure fails. Counted by `residual`.
ForwardEvaluation closeForData(const ValveCase& valve_case, const CordSet& cords,
                               const ForwardResidual& residual);

// Index of the successful evaluation with the lowest cost below `cost` (the first of equal
// costs), or -1 when none is below it.
int cheapestBelow(const std::vector<ForwardEvaluation>& evaluations, double cost);

// Full closures of `sets` from the open state, run on `threads` threads (one result slot per
// set: independent of the thread count); data residuals and the data-only cost. A failed
// closure has error set. Shared by the pre-fit stages. `on_closure`: as the options'.
std::vector<ForwardEvaluation> closeCordSets(
    const ValveCase& valve_case, const std::vector<CordSet>& sets, const ForwardResidual& residual,
    int threads, const std::function<void(int, int)>& on_closure = nullptr);

// The cords every pre-fit stage may change: neither locked nor set by the user (manual).
inline bool isFreeNonManual(const Cord& cord) {
  return !cord.locked && cord.provenance != Provenance::kManual;
}

// The seed with every free non-manual cord's rest length multiplied by `factor`.
CordSet scaleFreeCords(const CordSet& seed, double factor);
// The same with one factor per cord kind.
CordSet scaleFreeCords(const CordSet& seed, double primary_factor, double secondary_factor);
// The same, each scaled cord's scale (rest / seed_rest_length) kept within `bounds`: a seed
// whose cords are not at scale 1 (a fit's cords.json as the seed of another fit) would
// otherwise leave them, and the optimiser's start would be clamped back, losing the pre-fit.
CordSet scaleFreeCords(const CordSet& seed, double primary_factor, double secondary_factor,
                       const ParameterBounds& bounds);

}  // namespace chordfit::inverse
