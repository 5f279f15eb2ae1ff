// NLopt drivers (Steven G. Johnson, "The NLopt nonlinear-optimization package"): derivative-
// free, bounded, on the scalar cost 1/2 sum rho(r_i^2) + 1/2 |regularisation|^2:
//   bobyqa  NLOPT_LN_BOBYQA   (Powell's quadratic trust-region model; 2P+1 start points)
//   cobyla  NLOPT_LN_COBYLA   (linear approximations; may end on a point worse than its best)
//   sbplx   NLOPT_LN_SBPLX    (Rowan's subplex, Nelder-Mead on subspaces)
//   crs2    NLOPT_GN_CRS2_LM  (controlled random search, global; population 10 (P+1))
// Every cost evaluation is one full closure, sequentially (there is nothing to parallelise
// inside a derivative-free step; --threads does not change the run). The evaluation budget is
// the remaining forward-run budget; a closure that fails returns a large finite cost so the
// method backs off. NLopt's exceptions (roundoff_limited, forced_stop, runtime errors) end the
// run with a message; the best point seen is kept by the objective in every case.
#pragma once

#include "inverse/optimizer.h"

namespace chordfit::inverse {

class NloptDriver : public Optimizer {
 public:
  explicit NloptDriver(std::string algorithm) : algorithm_(std::move(algorithm)) {}
  std::string name() const override { return algorithm_; }
  Termination minimize(FitObjective& objective, const OptimizerSettings& settings) override;
  bool localDerivativeFree() const override { return algorithm_ != "crs2"; }

 private:
  std::string algorithm_;
};

}  // namespace chordfit::inverse
