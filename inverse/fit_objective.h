// What every optimiser driver works against: the forward residual with its bookkeeping
// (issue 5 item 3). It
//   - runs full closures from the open state (evaluate) and caches them by exact x, so a
//     driver asking twice for one point pays once;
//   - computes the data Jacobian at an evaluated point by parallel central differences, full
//     closures by default or warm-started from that point's closed state (--fd-warm;
//     finite_difference.h);
//   - counts forward simulations against a budget (max_sims) and the wall time;
//   - keeps the best full-closure evaluation seen: what a fit reports always comes from a
//     full closure, never from a warm-started perturbation, and never from a worse point an
//     optimiser happened to end on (COBYLA may not return its best point);
//   - records the convergence history (one record per driver iteration or evaluation).
// Not thread-safe: drivers call it from one thread; the parallelism is inside jacobian().
#pragma once

#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "inverse/finite_difference.h"
#include "inverse/forward_residual.h"

namespace chordfit::inverse {

struct IterationRecord {
  std::string stage;               // "seed", "prefit", or the optimiser's name
  int iteration = 0;               // driver iteration (Ceres) or evaluation (NLopt)
  double cost = 0.0;               // at the driver's current point
  double best_cost = 0.0;          // best full-closure cost so far
  double mean_deviation_mm = 0.0;  // at the driver's current point
  int forward_sims = 0;            // cumulative, all stages
  double elapsed_s = 0.0;          // since the fit started
};

class FitObjective {
 public:
  using Clock = std::chrono::steady_clock;
  // sims_before / start: forward runs already spent and the fit's start time (earlier stages).
  FitObjective(const ForwardResidual& residual, const FiniteDifferenceOptions& fd, int max_sims,
               int sims_before, Clock::time_point start,
               std::function<void(const IterationRecord&)> on_iteration);

  const ForwardResidual& residual() const { return residual_; }
  int parameterCount() const { return residual_.parameters().size(); }
  // Where a driver starts: the parameterisation's initial point, or the point restartAt gave.
  // The regularisation's prior stays at the initial point either way.
  const Eigen::VectorXd& startPoint() const { return start_x_; }
  void restartAt(const Eigen::VectorXd& x) { start_x_ = x; }
  // From now on, Jacobians come from full closures (no warm start); those computed warm are
  // forgotten. The Ceres driver's way out of warm-started differences that mispredict
  // (ceres_driver.h).
  void useFullClosureDifferences();
  bool warmDifferences() const { return fd_.warm_start; }
  // The finite differences in use now (after useFullClosureDifferences, without warm start):
  // what a Jacobian computed after the solve must use too.
  const FiniteDifferenceOptions& finiteDifferences() const { return fd_; }
  // Where a long Jacobian says it is still running (closureHeartbeat); none by default.
  void setProgress(std::function<void(const std::string&)> say) { progress_ = std::move(say); }
  // The stage name history records carry instead of the driver's own (empty: the driver's).
  void setStageLabel(std::string label) { stage_label_ = std::move(label); }

  // Full closure at x (cached). Counts one forward run when not cached. Failed closures are
  // returned with error set and never become the best.
  std::shared_ptr<const ForwardEvaluation> evaluate(const Eigen::VectorXd& x);
  // Data Jacobian (#data by #parameters) at x (evaluates x first if needed); 2 runs per
  // parameter that moves a taut cord. nullptr and `error` set when a closure failed.
  std::shared_ptr<const Eigen::MatrixXd> jacobian(const Eigen::VectorXd& x, std::string& error);

  // The budget is enforced here too: a closure (or Jacobian) that would exceed it is not run;
  // evaluate() then returns an evaluation with error set, jacobian() nullptr.
  bool budgetRefused() const { return budget_refused_; }
  int forwardSims() const { return sims_; }
  int maxSims() const { return max_sims_; }
  bool budgetAllows(int more_sims) const { return sims_ + more_sims <= max_sims_; }
  // Forward runs of a Jacobian: 2 per parameter, at x (when its closure is cached) only for
  // the parameters that do not move slack cords alone (finite_difference.h).
  int jacobianSims() const { return 2 * parameterCount(); }
  int jacobianSims(const Eigen::VectorXd& x);
  double elapsedSeconds() const;

  std::shared_ptr<const ForwardEvaluation> best() const { return best_; }
  // Adds a full closure run elsewhere (e.g. the pre-fit's best) to the cache, uncounted.
  void remember(const ForwardEvaluation& evaluation);
  // The closure run or remembered last (a rejected trial step's, in the Ceres driver), or
  // nullptr before any.
  std::shared_ptr<const ForwardEvaluation> latest() const {
    return cache_.empty() ? nullptr : cache_.back().evaluation;
  }
  // Forward runs of the last Jacobian the budget refused (0: none refused).
  int refusedJacobianSims() const { return refused_jacobian_sims_; }
  // The cached full closure at x, or nullptr (no forward run).
  std::shared_ptr<const ForwardEvaluation> cached(const Eigen::VectorXd& x);
  // The Jacobian computed at x, if it is still cached, or nullptr (no forward run).
  std::shared_ptr<const Eigen::MatrixXd> cachedJacobian(const Eigen::VectorXd& x);
  // Appends a history record for the driver's current point and calls on_iteration.
  void recordIteration(const std::string& stage, int iteration, double cost,
                       double mean_deviation_mm);
  const std::vector<IterationRecord>& history() const { return history_; }

 private:
  struct Entry {
    std::shared_ptr<const ForwardEvaluation> evaluation;
    std::shared_ptr<const Eigen::MatrixXd> jacobian;
  };
  Entry* find(const Eigen::VectorXd& x);

  const ForwardResidual& residual_;
  FiniteDifferenceOptions fd_;
  Eigen::VectorXd start_x_;
  std::string stage_label_;
  int max_sims_;
  int sims_;
  bool budget_refused_ = false;
  int refused_jacobian_sims_ = 0;
  Clock::time_point start_;
  std::function<void(const IterationRecord&)> on_iteration_;
  std::function<void(const std::string&)> progress_;
  std::deque<Entry> cache_;  // most recent last; a few entries suffice (LM: current + trial)
  std::shared_ptr<const ForwardEvaluation> best_;
  std::vector<IterationRecord> history_;
};

}  // namespace chordfit::inverse
