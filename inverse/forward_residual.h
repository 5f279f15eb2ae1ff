// The fit's residual (DESIGN §7, issue 5 item 2): the forward closure as a black box.
//
// Data residuals: one per tracing point, r_i = distance (mm) from the point to the closed
// surface of its own leaflet (exact point-to-triangle; the tracing reader labels each polyline
// with its leaflet), or to the whole closed mesh for unlabelled points or with own_leaflet
// false (then their mean is the AvgD of the paper's Table 1). Why the own leaflet: with
// whole-mesh distances, points traced on a flipped posterior flap over the valve centre are
// explained as well by an anterior bulge, and the fit can settle there (prolapse-P2 and
// flail-P2 seeds 2: the fits bulged in A1 and A3; docs/fitting.md). They go through Huber's
// loss (robust_loss.h) with delta = huber_delta_mm: tracings are noisy and have outliers, and
// a point beyond delta should pull linearly, not quadratically.
//
// Section residuals (section_weight > 0): one per tracing plane and leaflet,
// r = sqrt(section_weight * E) with E the stray section of core/section_mismatch.h (how much of
// the closed mesh, cut by the plane, lies farther than a tolerance from that leaflet's
// tracings), appended to the data residuals without a loss: E already tolerates noise and
// caps each stray point. Why: the point residuals never ask whether the mesh has tissue where
// nothing was traced, and fits parked a prolapsing P2 flap flat over the valve centre, through
// three planes with no tissue traced there, so the sections (and Table 1's prolapse verdict)
// showed P1, P2 and P3 where the tracings show P2 (docs/fitting.md, "Section term").
//
// Regularisation residuals (linear in x, r = A x - b, no loss):
//   seed       w_seed * (s_c - s0_c) per scale parameter: toward the starting value (seed or
//              manual, after the pre-fits: the parameterisation's initial point);
//   neighbour  w_neighbour * ((s_c - s0_c) - (s_d - s0_d)) for neighbouring cords c, d: same
//              group (leaflet x tip), same kind, adjacent in annulus angle; the correction to
//              the prior should vary smoothly along the annulus;
//   tips       w_tip_per_mm * offset, per tip offset coordinate.
// Why: a cord that is slack in the closed state, or far from every tracing plane, moves no
// tracing point; its data gradient is zero and the problem is singular without a prior. The
// weights are chosen small against the data: a cord attached near a plane moves ~10-30 tracing
// points by 1-3 mm for a 10 % scale change (cost change ~1-50), while w_seed = 0.5 mm charges a
// 10 % deviation 0.5 * (0.05)^2 ~ 1e-3. So the prior decides only where the data are silent,
// and the neighbour term (4x stronger) makes silent cords follow their identified neighbours
// rather than the seed.
#pragma once

#include <atomic>

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"
#include "core/cord_insertion.h"
#include "core/section_mismatch.h"
#include "core/simulator.h"
#include "inverse/fit_parameters.h"

namespace chordfit::inverse {

struct RegularisationWeights {
  double seed = 0.5;         // mm per unit scale
  double neighbour = 2.0;    // mm per unit scale difference
  double tip_per_mm = 0.05;  // mm of residual per mm of tip offset
};

struct ResidualOptions {
  double huber_delta_mm = 1.0;  // ~3x the tracing noise SD of the synthetic cohort (0.3 mm)
  // true: a labelled tracing point is measured to its own leaflet's surface
  // (pointToOwnLeafletDistances, metrics.h); unlabelled points to the whole mesh. false: every
  // point to the whole mesh, the Table 1 AvgD itself.
  bool own_leaflet = true;
  // Weight of the section residuals (see above); 0: none.
  double section_weight = 0.0;
  SectionMismatchOptions section;
  RegularisationWeights weights;
};

// One full evaluation of the residual at a parameter vector.
struct ForwardEvaluation {
  Eigen::VectorXd x;
  Eigen::VectorXd data;            // #tracing points (mm), then the section residuals
  Eigen::VectorXd regularisation;  // A x - b
  double cost = 0.0;               // 1/2 sum rho(data^2) + 1/2 |regularisation|^2
  double mean_deviation_mm = 0.0;  // AvgD: mean whole-mesh distance (= mean of data when
                                   // the residual is not own-leaflet)
  Eigen::MatrixXd closed_V;        // #V by 3 closed state
  bool converged = false;
  bool warm_started = false;  // true only for finite-difference perturbations
  std::string error;          // simulation failure; the other fields are then meaningless
  bool ok() const { return error.empty(); }
};

class ForwardResidual {
 public:
  ForwardResidual(const ValveCase& valve_case, const FitParameterization& parameters,
                  const SimulationSettings& settings, const ResidualOptions& options);

  const ValveCase& valveCase() const { return case_; }
  // Where each cord inserts, as the closures spread it (cord_insertion.h; the same for every x).
  const std::vector<CordInsertionWeights>& cordInsertions() const { return insertions_; }
  const FitParameterization& parameters() const { return parameters_; }
  // Data residuals: pointCount() tracing-point distances (Huber loss), then the section
  // residuals (no loss).
  int dataCount() const { return pointCount() + sectionCount(); }
  int pointCount() const { return static_cast<int>(tracing_points_.rows()); }
  int sectionCount() const { return options_.section_weight > 0.0 ? sections_.termCount() : 0; }
  int regularisationCount() const { return static_cast<int>(A_.rows()); }
  const ResidualOptions& options() const { return options_; }
  const SimulationSettings& settings() const { return settings_; }

  // Closes the valve with the cords of x and evaluates every residual. warm_start: a closed
  // state to start from (finite-difference perturbations only; see simulator.h). Thread-safe.
  ForwardEvaluation evaluate(const Eigen::VectorXd& x,
                             const Eigen::MatrixXd* warm_start = nullptr) const;

  // Data residuals of a closed state: own-leaflet or whole-mesh distances (options), then the
  // section residuals.
  Eigen::VectorXd dataResiduals(const Eigen::MatrixXd& closed_V) const;
  // Whole-mesh distances of every tracing point: their mean is the Table 1 AvgD.
  Eigen::VectorXd surfaceDistances(const Eigen::MatrixXd& closed_V) const;
  // AvgD of a closed state whose data residuals are `data`.
  double meanDeviation(const Eigen::MatrixXd& closed_V, const Eigen::VectorXd& data) const;
  // Regularisation r = A x - b and its (constant) Jacobian A.
  Eigen::VectorXd regularisation(const Eigen::VectorXd& x) const { return A_ * x - b_; }
  const Eigen::MatrixXd& regularisationJacobian() const { return A_; }
  // 1/2 sum rho(point residual^2) + 1/2 |section residuals|^2 + 1/2 |regularisation|^2.
  double cost(const Eigen::VectorXd& data, const Eigen::VectorXd& regularisation) const;

  // Neighbour pairs (cord indices) used by the regularisation.
  const std::vector<std::pair<int, int>>& neighbourPairs() const { return neighbours_; }

  // Closures run for this residual (evaluate, and the pre-fit stages through
  // countClosure) that reached their step cap without settling; their states are the mean
  // over the final steps (simulator.h, average_unsettled_steps). Thread-safe.
  void countClosure(const SimulationResult& result) const {
    if (result.ok() && !result.converged) ++unsettled_closures_;
  }
  int unsettledClosures() const { return unsettled_closures_.load(); }

 private:
  const ValveCase& case_;
  const FitParameterization& parameters_;
  SimulationSettings settings_;
  std::vector<CordInsertionWeights> insertions_;
  ResidualOptions options_;
  Eigen::MatrixXd tracing_points_;
  Eigen::VectorXi tracing_leaflets_;  // per point, -1 unlabelled
  Eigen::VectorXi face_leaflets_;     // per face of the case mesh
  SectionMismatch sections_;
  std::vector<std::pair<int, int>> neighbours_;
  Eigen::MatrixXd A_;
  Eigen::VectorXd b_;
  mutable std::atomic<int> unsettled_closures_{0};
};

// Pairs of free cords adjacent along the annulus within the same group and kind, ordered by
// the angle of their leaflet vertex around the open annulus centre.
std::vector<std::pair<int, int>> neighbouringCords(const ValveCase& valve_case,
                                                   const FitParameterization& parameters);

}  // namespace chordfit::inverse
