// Segment pre-fit: after the global factor (global_prefit.h), one derivative-free pass over
// the six Carpentier segments, each trying a few common scales for its free cords.
//
// Why: a prolapse is a snap, not a slope. Tracings of a prolapsing P2 scallop ask for P2
// cords half again as long as their neighbours (the cohort's P2 truth: 1.5 x normal), but
// from the global factor the P2 cords are taut and the scallop sits below the annulus; a
// small change of their length moves it little, and the gradient points to the nearest
// local minimum, which keeps the scallop down. A grid per segment can jump across. This is
// the paper's manual workflow at a finer grain (its user scales groups of cords until the
// closed valve matches the tracings).
//
// One pass, segments in Carpentier order (A1, A2, A3, P1, P2, P3): for segment s, every
// free non-manual cord whose leaflet vertex lies in s (open-state position, as the prolapse
// measure localises) is set to scale t for each t of a grid over the scale bounds; the
// candidates close in parallel, and the best t is kept if it lowers the data cost
// 1/2 sum rho(r^2). The next segment starts from the cords so far, so the pass is a
// coordinate descent. Manual and locked cords keep their values.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/case_data.h"
#include "core/cordset.h"
#include "inverse/fit_parameters.h"
#include "inverse/forward_residual.h"

namespace chordfit::inverse {

struct SegmentPrefitOptions {
  bool enabled = true;
  int points = 5;  // scales tried per segment: a grid over [scale_lower, scale_upper]
  int threads = 2;
  // Progress of the stage's closures (FiniteDifferenceOptions::on_closure); optional.
  std::function<void(int, int)> on_closure;
};

struct SegmentPrefitResult {
  CordSet start;                      // the input set with the accepted segment scales
  ForwardEvaluation best;             // full closure of `start`
  std::vector<std::string> changed;   // "P2 1.3", one per accepted segment, in order
  std::vector<int> changed_segments;  // their segment ids (openStateSegments), same order
  int forward_sims = 0;
};

// start_evaluation: the closure of `start` (already run, not repeated).
SegmentPrefitResult segmentScalePrefit(const ValveCase& valve_case, const CordSet& start,
                                       const ForwardEvaluation& start_evaluation,
                                       const ParameterBounds& bounds,
                                       const ForwardResidual& residual,
                                       const SegmentPrefitOptions& options);

}  // namespace chordfit::inverse
