// Tissue pre-fit (opt-in, `chordfit fit --tissue-prefit`; also the fit's tissue retry,
// fit_cords.h): after the cord pre-fits, one pass over the Carpentier segments trying a softer
// leaflet tissue in each.
//
// Why: cords alone cannot make every prolapse. An anterior leaflet has no clefts, so A2 cannot
// rise past the annulus without A1 and A3 however long its cords are, and a P3 scallop is held
// by its commissure; degenerative (myxomatous) tissue is softer and more extensible (Barber
// et al., J Heart Valve Dis 2001), and the cohort's prolapse-A2/P3 truths prolapse only
// through such lesion tissue (experiments/README.md, "Calibration"). A fit that assumes uniform
// tissue then ends at 2-4x the noise floor on those cases whatever the cords; given the true
// lesion it reaches 1.4-1.6x (docs/fitting.md). Softening is a snap, like a prolapse: halving
// the stiffness barely moves a segment, a tenth of it can lift it 2-3 mm, so a grid, not a
// gradient.
//
// Candidates: for a segment s, every leaflet vertex in s (open-state position, as the
// prolapse measure localises) gets its tissue factor multiplied by f, for each f of `factors`,
// once with the cords as they are and once with the segment's free non-manual cords at the
// upper scale bound (a lesion's cords are long too: a soft segment held by short cords only
// bulges between them). Greedy, best first: each round closes the candidates of every segment
// not yet changed, in parallel, from the same start, and keeps the best if it lowers the data
// cost (a pass in a fixed order let A3, tried first, take P3's lesion on the cohort); at most
// `rounds` rounds (66 closures for two). The tissue found is piecewise constant per segment;
// the cords are then optimised on it. It is a hypothesis the user opts into: on tracings alone a
// soft segment and long cords can explain the same bulge. The fit also runs it, on the segments
// concerned only, when the cords alone missed a prolapse the tracings show (the tissue retry,
// fit_cords.h).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"
#include "core/cordset.h"
#include "inverse/fit_parameters.h"
#include "inverse/forward_residual.h"

namespace chordfit::inverse {

struct TissuePrefitOptions {
  bool enabled = false;
  std::vector<double> factors{0.3, 0.1, 0.05};  // stiffness factors tried per segment
  int rounds = 2;  // segments accepted at most (one per round, best first)
  int threads = 2;
  // The segments tried (open-state segment ids); empty: every segment. The fit's tissue retry
  // tries those where the tracings show a prolapse its closure lacks.
  std::vector<int> segments;
  // Progress of the stage's closures (FiniteDifferenceOptions::on_closure: called from the
  // worker threads with the closures done and the most the stage runs); optional.
  std::function<void(int, int)> on_closure;
  // Closures of all rounds at most: 2 per factor and segment, fewer segments each round.
  int closures(int segments = 6) const {
    int total = 0;
    for (int r = 0; r < rounds && r < segments; ++r)
      total += 2 * static_cast<int>(factors.size()) * (segments - r);
    return total;
  }
};

struct TissuePrefitResult {
  CordSet start;                     // the input set, with long cords where accepted
  Eigen::VectorXd tissue;            // per-vertex factors (empty when nothing was accepted)
  ForwardEvaluation best;            // full closure of `start` on `tissue`
  std::vector<std::string> changed;  // "A2 0.1" or "A2 0.1, cords 1.5", per accepted segment
  int forward_sims = 0;
};

// start_evaluation: the closure of `start` on the case's own tissue (already run).
TissuePrefitResult segmentTissuePrefit(const ValveCase& valve_case, const CordSet& start,
                                       const ForwardEvaluation& start_evaluation,
                                       const ParameterBounds& bounds,
                                       const ForwardResidual& residual,
                                       const TissuePrefitOptions& options);

}  // namespace chordfit::inverse
