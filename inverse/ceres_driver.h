// Ceres Solver driver: trust-region Levenberg-Marquardt with parameter bounds.
//
// Problem layout: one parameter block (all P parameters, with their bounds); one residual
// block per tracing point, each with its own ceres::HuberLoss (a loss applies to a whole
// block, so per-point blocks make it robust per point); one block for the linear
// regularisation (analytic Jacobian, no loss). The data blocks share the FitObjective: the
// first block evaluated at a new x runs the closure (and, when Ceres asks for Jacobians, the
// parallel central differences), the others read the cache. Ceres itself runs on one thread
// (num_threads = 1); the parallelism is over the finite-difference closures.
//
// Budget: a Levenberg-Marquardt iteration costs one closure for the trial point plus 2P for
// the Jacobian when the step is accepted. The solve goes on while one trial closure fits (the
// iteration callback stops it when none is left); an accepted trial whose Jacobian the budget
// refuses ends it and is kept as the best point. The run never exceeds the budget.
//
// Warm-started differences (--fd-warm): a warm-started perturbation can settle on another
// branch than the full closure, and the Jacobian then mispredicts the cost. After
// OptimizerSettings::warm_rejections_before_full valid steps in a row rejected, the solve
// stops (when a full-closure Jacobian and a trial still fit the budget) and a second solve
// goes on from the best point with full-closure differences, recorded as stage "ceres-full".
// It starts with a fresh trust region and its own max_iterations. The prior stays at the
// first solve's start, so both minimise the same cost.
#pragma once

#include "inverse/optimizer.h"

namespace chordfit::inverse {

class CeresDriver : public Optimizer {
 public:
  std::string name() const override { return "ceres"; }
  Termination minimize(FitObjective& objective, const OptimizerSettings& settings) override;
};

// Silences glog (Ceres' logger) once per process: only errors reach stderr.
void quietCeresLogging();

}  // namespace chordfit::inverse
