// Central-difference Jacobian of the data residuals (DESIGN §7, issue 5 item 2).
//
//   J(:, p) = (r(x + h_p e_p) - r(x - h_p e_p)) / (2 h_p)
//
// Central differences: truncation error O(h^2) against O(h) for forward ones, for twice the
// forward runs. The step h must stand well above the forward map's noise: the closure stops
// at a quasi-static equilibrium within a tolerance (simulator.h), so r(x) is reproducible only
// to some epsilon; the derivative error is then ~epsilon / h. Steps and their measurement:
// docs/fitting.md ("Finite-difference step").
//
// The 2P perturbed closures are independent: they run on `threads` threads, each writing its
// own column, so J does not depend on the thread count or the order of completion. Each may
// warm-start from the base closed state (far fewer time steps; both sides of a difference
// start from the same state), but a warm-started closure can settle in a different
// equilibrium than the full closure the reported value comes from (contact, slack cords), so
// the default is a full closure for every perturbation.
//
// Parameters whose perturbations touch only cords that stay slack in the base closed state
// get a zero column without a closure (skip_slack): a cord exerts no force while its span is
// below its rest length (paper eq. 1), so the base state is the equilibrium of either
// perturbation too and the exact derivative is 0; a closure would only add the solver's noise
// and spend two forward runs. After the pre-fit most cords near no tracing plane are slack
// (25 of 33 at the end of the quick-start fit), so this is most of a Jacobian's cost.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/parallel_for.h"
#include "inverse/forward_residual.h"

namespace chordfit::inverse {

struct FiniteDifferenceOptions {
  double scale_step = 0.01;  // on a scale (dimensionless), see docs/fitting.md
  double tip_step_mm = 0.1;  // on a tip offset coordinate, mm
  // Start perturbed closures from the base closed state. Off by default: measured on the
  // bundled small case, warm-started differences stalled the fit (the warm-started
  // equilibrium is not the one a full closure reaches; docs/fitting.md).
  bool warm_start = false;
  int threads = 2;
  // Zero columns for parameters that only move slack cords (see above), and the slack a cord
  // must keep at the base closed state under the perturbation to count: above the step
  // between the solver's tolerance and the residual motion of a closure that did not settle
  // (its state is the mean of its last steps, vertices moving ~0.01-0.1 mm; simulator.h).
  bool skip_slack = true;
  double slack_margin_mm = 0.1;
  // Called after each perturbed closure with (closures done, closures in all), from the
  // worker threads: it must be thread-safe. Progress only (closureHeartbeat); optional.
  std::function<void(int, int)> on_closure;
};

// An on_closure that says `what` is still running ("jacobian: 20 of 66 closures, 41 s") through
// `say`, at most every `every_s` seconds and not before the Jacobian has run that long: a
// Jacobian of a ~2,000-vertex valve runs for a minute or more with nothing else printed.
std::function<void(int, int)> closureHeartbeat(std::function<void(const std::string&)> say,
                                               std::string what, double every_s = 10.0);
// The same for a stage that runs its closures in several batches (the pre-fits): it counts
// them itself across the batches ("segment pre-fit: 17 closures so far, 21 s").
std::function<void(int, int)> stageHeartbeat(std::function<void(const std::string&)> say,
                                             std::string what, double every_s = 10.0);

struct JacobianResult {
  Eigen::MatrixXd J;         // #data by #parameters
  int forward_sims = 0;      // closures run (2 per parameter that is not slack)
  int slack_parameters = 0;  // parameters given a zero column without closures
  std::string error;         // first failed perturbation, if any (J is then unusable)
  bool ok() const { return error.empty(); }
};

// base_closed: the closed state at x (warm start of the perturbations; ignored when
// options.warm_start is false).
JacobianResult centralDifferenceJacobian(const ForwardResidual& residual, const Eigen::VectorXd& x,
                                         const Eigen::MatrixXd& base_closed,
                                         const FiniteDifferenceOptions& options);

// Per parameter: true when both of its perturbations (x +- step) change only cords whose span
// at base_closed stays below their perturbed rest length by more than the margin (closedSpans,
// cord_insertion.h, with the cords' insertions as the closures spread them:
// ForwardResidual::cordInsertions), so its column is exactly zero. All false without
// skip_slack.
std::vector<bool> slackParameters(const FitParameterization& parameters,
                                  const std::vector<CordInsertionWeights>& insertions,
                                  const Eigen::VectorXd& x, const Eigen::MatrixXd& base_closed,
                                  const FiniteDifferenceOptions& options);

}  // namespace chordfit::inverse
