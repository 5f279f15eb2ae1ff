// One interface for every optimiser driver, chosen by name (issue 5 item 3):
//   ceres   trust-region Levenberg-Marquardt (Ceres Solver) with parameter bounds, Huber loss
//           on the data residuals, central-difference Jacobian (ceres_driver.h);
//   bobyqa, cobyla, sbplx   NLopt local derivative-free methods;
//   crs2    NLopt controlled random search with local mutation (global, bounded).
// A driver starts at the parameterisation's initial point, stays within its bounds, spends at
// most the objective's budget of forward runs and records one history entry per iteration
// (Ceres) or evaluation (NLopt). The result is read from the objective (best full closure).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "inverse/fit_objective.h"

namespace chordfit::inverse {

struct OptimizerSettings {
  int max_iterations = 100;
  // Stop when the relative cost decrease of a step falls below this (Ceres
  // function_tolerance, NLopt ftol_rel).
  double function_tolerance = 1e-4;
  // Stop when a step changes x by less than this, relative (Ceres parameter_tolerance,
  // NLopt xtol_rel).
  double parameter_tolerance = 1e-4;
  // Initial step of derivative-free methods: on scales (dimensionless) and tip offsets (mm).
  double initial_scale_step = 0.05;
  double initial_tip_step_mm = 1.0;
  std::uint32_t random_seed = 1;             // crs2: same seed => same run
  double initial_trust_region_radius = 1.0;  // ceres (Levenberg-Marquardt: 1 / initial mu)
  // ceres with warm-started differences: after this many rejected steps in a row, the solve
  // goes on from its best point with full-closure differences (0: never). A rejected step is
  // a Jacobian that mispredicted the cost; a warm-started perturbation that settled on
  // another branch than the full closure is the usual cause (ceres_driver.h).
  int warm_rejections_before_full = 2;
};

// How a driver's run ended. `budget_spent`: it stopped because --max-sims allowed no further
// closure it needed (the caller then says where the rest of the budget went).
struct Termination {
  std::string message;
  bool budget_spent = false;
};

class Optimizer {
 public:
  virtual ~Optimizer() = default;
  virtual std::string name() const = 0;
  // Minimises objective's cost from its initial point. Returns a short termination message
  // ("converged: ...", "budget of N forward runs reached", "nlopt: roundoff limited", ...).
  // Never throws for optimiser trouble: the best point seen stays in the objective.
  virtual Termination minimize(FitObjective& objective, const OptimizerSettings& settings) = 0;
  // A local derivative-free method that stops on a small relative change of the cost between
  // evaluations, which a simulator's map can meet far from a minimum (NLopt's bobyqa, cobyla,
  // sbplx); `chordfit fit` then notes an early stop.
  virtual bool localDerivativeFree() const { return false; }
};

// nullptr for an unknown name.
std::unique_ptr<Optimizer> makeOptimizer(const std::string& name);
const std::vector<std::string>& optimizerNames();  // ceres, bobyqa, cobyla, sbplx, crs2

}  // namespace chordfit::inverse
