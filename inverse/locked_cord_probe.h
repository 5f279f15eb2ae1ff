// What the user's locks cost the fit: a probe of each locked cord after the fit.
//
// Why: a locked cord is a constant of the fit (the paper's editor; issue 5 item 5), so when the
// user locks a cord at a length the tracings contradict, the fit can only work around it, and
// nothing in its output said so. Measured on the bundled prolapse-P2 case: from the quick-start
// fit's cords with the P2 cords set to 0.75 of their seed lengths and locked, the fit stopped on
// Ceres' gradient tolerance after 51 closures at AvgD 1.32 mm, every free cord slack, and the
// tracings' P2 prolapse not reconstructed; the report showed a converged fit.
//
// What: for each locked cord taut in the fitted closure (a slack one pulls on nothing there,
// so a small change of it changes nothing), the other cords as fitted:
//   - the derivative of the data residuals with respect to the cord's length, by central
//     differences over rest length l (1 +- h) (full closures; h = the fit's scale step);
//   - the one-parameter Gauss-Newton step of the data cost C = 1/2 sum rho(r_i^2) (Huber,
//     robust_loss.h) under its IRLS weights w_i (huberWeights):
//       g = sum w_i r_i j_i,  H = sum w_i j_i^2,  delta = -g / H; the predicted drop of the
//     step d actually applied (capped, bounded below) is -(g d + H d^2 / 2), g^2 / 2H uncapped
//     (Nocedal and Wright 2006, "Numerical Optimization", sec. 10.3). With the free cords
//     re-fitting too the drop could only be larger (a lower bound of the linearised gain);
//   - one full closure at l (1 + delta), the relative change capped at max_change and the scale
//     kept within the fit's scale bounds (or the cord's own scale when that lies outside):
//     what unlocking this cord alone would give, measured, not only predicted;
//   - per Carpentier segment with two or more taut locked cords, the same for its cords
//     together: the Gauss-Newton step of the small system (J^T W J + mu I) delta = -J^T W r
//     with a Levenberg damping mu = 1e-3 trace / n against nearly parallel columns (cords
//     holding one flap), then one closure.
// 3 closures per taut locked cord and one per such segment, run after the fit outside its
// budget, `threads` at a time; each closure is independent, so the result does not depend on
// the thread count.
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

struct LockedCordProbeOptions {
  double relative_step = 0.01;  // h, on the cord's length (the fit's --fd-step)
  double max_change = 0.25;     // cap on |delta|
  int threads = 2;
  // Before the closures, when there are taut locked cords: a line saying how many and how many
  // closures at most (optional; `chordfit fit` prints it).
  std::function<void(const std::string&)> on_start;
  // Progress of the closures (closeCordSets' on_closure, called from the worker threads with
  // the closures done and the count of each of the probe's two batches); optional.
  std::function<void(int, int)> on_closure;
};

// One trial: the listed locked cords at new lengths, every other cord as fitted.
struct LockedCordTrial {
  std::vector<int> cords;          // cord indices, ascending
  std::vector<double> lengths_mm;  // their probe lengths l (1 + delta), capped and bounded
  double predicted_drop = 0.0;     // the linear model's drop for the step as applied (capped,
                                   // bounded), a fraction of the fit's data cost
  double data_cost = 0.0;          // of the closure at the probe lengths
  double mean_deviation_mm = 0.0;  // AvgD of that closure
  std::string error;               // a closure failed (then the numbers are unset)
  bool ok() const { return error.empty() && !cords.empty(); }
};

struct LockedCordProbe {
  int cord = -1;
  bool slack = false;    // at the fitted closure: not probed (trial is empty)
  double span_mm = 0.0;  // its span in the fitted closure
  LockedCordTrial trial;
};

// The taut locked cords of one Carpentier segment moved together (when it has two or more):
// a flap held by several locked cords does not move when one of them is let go.
struct LockedSegmentProbe {
  int segment = -1;  // Carpentier segment id (openStateSegments of the cords' vertices)
  LockedCordTrial trial;
};

struct LockedCordProbes {
  std::vector<LockedCordProbe> cords;        // every locked cord, in cord order
  std::vector<LockedSegmentProbe> segments;  // ascending segment id
  double fit_data_cost = 0.0;                // the fitted closure's, for reference
  double fit_mean_deviation_mm = 0.0;
  double relative_step = 0.0, max_change = 0.0;  // the options it ran with
  int forward_sims = 0;
  int unsettled_sims = 0;  // of forward_sims: closures that reached their step cap
  double seconds = 0.0;
  // The trial (single cords, then segments) with the lowest data cost below the fit's, or
  // nullptr when none lowered it.
  const LockedCordTrial* best() const;
};

// fitted: the fitted set (its locked cords are probed); fitted_evaluation: its closure
// (data residuals and closed state, from `residual`); closed_spans: per cord, its span there
// (closedSpans); valve_case: the case the fit closed (with its fitted tissue, if any).
LockedCordProbes probeLockedCords(const ValveCase& valve_case, const CordSet& fitted,
                                  const ForwardEvaluation& fitted_evaluation,
                                  const Eigen::VectorXd& closed_spans,
                                  const ForwardResidual& residual, const ParameterBounds& bounds,
                                  const LockedCordProbeOptions& options);

}  // namespace chordfit::inverse
