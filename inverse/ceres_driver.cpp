#include "inverse/ceres_driver.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <mutex>
#include <vector>

#include <ceres/ceres.h>
#include <glog/logging.h>

#include "core/counted.h"

namespace chordfit::inverse {

namespace {

Eigen::VectorXd toVector(const double* x, int n) { return Eigen::Map<const Eigen::VectorXd>(x, n); }

// Data residual i (tracing point i's distance to the closed surface, or a section residual);
// its Jacobian row comes from the objective's central differences at x.
class DataPointCost : public ceres::CostFunction {
 public:
  DataPointCost(FitObjective& objective, int point) : objective_(objective), point_(point) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(objective.parameterCount());
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int n = objective_.parameterCount();
    const Eigen::VectorXd x = toVector(parameters[0], n);
    const auto evaluation = objective_.evaluate(x);
    if (!evaluation->ok()) return false;  // Ceres treats the step as invalid and shrinks
    residuals[0] = evaluation->data(point_);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      std::string error;
      const auto J = objective_.jacobian(x, error);
      if (!J) return false;
      for (int p = 0; p < n; ++p) jacobians[0][p] = (*J)(point_, p);
    }
    return true;
  }

 private:
  FitObjective& objective_;
  int point_;
};

// r = A x - b, Jacobian A (row-major for Ceres).
class RegularisationCost : public ceres::CostFunction {
 public:
  explicit RegularisationCost(const ForwardResidual& residual) : residual_(residual) {
    set_num_residuals(residual.regularisationCount());
    mutable_parameter_block_sizes()->push_back(residual.parameters().size());
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::MatrixXd& A = residual_.regularisationJacobian();
    const Eigen::VectorXd r = residual_.regularisation(toVector(parameters[0], A.cols()));
    Eigen::Map<Eigen::VectorXd>(residuals, r.size()) = r;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          jacobians[0], A.rows(), A.cols()) = A;
    }
    return true;
  }

 private:
  const ForwardResidual& residual_;
};

class ProgressAndBudget : public ceres::IterationCallback {
 public:
  // warm_rejections: rejected steps in a row after which a solve on warm-started differences
  // stops so the driver can go on with full closures (0: never).
  ProgressAndBudget(FitObjective& objective, const std::vector<double>& x, int warm_rejections)
      : objective_(objective), x_(x), warm_rejections_(warm_rejections) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    // After a rejected step x stays where it was, but Ceres reports the trial point's cost
    // (measured: costs above the best with one closure each); the trial is the closure run
    // last, so its AvgD goes with that cost.
    const auto at = summary.step_is_successful
                        ? objective_.cached(toVector(x_.data(), static_cast<int>(x_.size())))
                        : objective_.latest();
    // A trial whose closure failed has no AvgD, and Ceres gives it the cost DBL_MAX: NaN for
    // both (a gap in the history, not a 0 mm AvgD or a 1e308 cost on the plot's axis).
    const bool failed = !at || !at->ok() || !(summary.cost < 0.5 * DBL_MAX);
    objective_.recordIteration("ceres", summary.iteration, failed ? NAN : summary.cost,
                               failed ? NAN : at->mean_deviation_mm);
    // Go on while a trial step fits: it needs one closure and uses the Jacobian at x, already
    // computed. When an accepted trial's own Jacobian no longer fits, jacobian() refuses it
    // and the solve ends there, the trial kept as the best point seen. (Stopping as soon as
    // a trial *and* its Jacobian no longer fit left up to a Jacobian's worth of the budget
    // unused, and a fit without a single step after its first Jacobian.)
    if (!objective_.budgetAllows(1)) {
      budget_reached = true;
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    // Iteration 0 is the start, not a step. A trial whose closure failed is no misprediction
    // of the Jacobian: it neither counts nor breaks a run.
    if (summary.iteration == 0 || summary.step_is_successful)
      rejected_in_a_row_ = 0;
    else if (summary.step_is_valid)
      ++rejected_in_a_row_;
    if (warm_rejections_ > 0 && objective_.warmDifferences() &&
        rejected_in_a_row_ >= warm_rejections_ && fullRestartFits()) {
      warm_distrusted = true;
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    return ceres::SOLVER_CONTINUE;
  }
  bool budget_reached = false;
  bool warm_distrusted = false;  // stopped for rejected steps on warm-started differences

 private:
  // The full-closure solve needs a Jacobian at the best point and one trial; when they do not
  // fit, the warm solve goes on with trial steps (1 closure each) instead.
  bool fullRestartFits() {
    const auto best = objective_.best();
    return best && objective_.budgetAllows(objective_.jacobianSims(best->x) + 1);
  }

  FitObjective& objective_;
  const std::vector<double>& x_;  // Ceres updates it every iteration
  int warm_rejections_;
  int rejected_in_a_row_ = 0;
};

// One Levenberg-Marquardt solve from the objective's start point.
struct SolveResult {
  Termination termination;
  bool warm_distrusted = false;
};

}  // namespace

void quietCeresLogging() {
  static std::once_flag once;
  std::call_once(once, [] {
    // Ceres logs at ERROR what the driver reports itself: "Terminating: Residual and Jacobian
    // evaluation failed" is the budget refusing a Jacobian (the termination says so), and a
    // new user read the glog line on stderr as a failure. Only fatal ones pass.
    FLAGS_minloglevel = google::GLOG_FATAL;
    FLAGS_logtostderr = true;
    if (!google::IsGoogleLoggingInitialized()) google::InitGoogleLogging("chordfit");
  });
}

namespace {

SolveResult solveFromStart(FitObjective& objective, const OptimizerSettings& settings) {
  const ForwardResidual& residual = objective.residual();
  const FitParameterization& parameters = residual.parameters();
  const int n = parameters.size();
  const Eigen::VectorXd& start = objective.startPoint();
  std::vector<double> x(start.data(), start.data() + n);
  // An unknown start (the seed clamped into the bounds) is closed first when the budget holds
  // it, so that its Jacobian is counted as it will be run: only the parameters that move a taut
  // cord there. Counted for every parameter, the check refused starts one Jacobian of 6
  // closures could move ("66 runs, 65 left"). Ceres evaluates the start first anyway.
  bool start_known = objective.cached(start) != nullptr;
  std::shared_ptr<const ForwardEvaluation> closed_here;  // the start's closure, when run here
  if (!start_known && objective.budgetAllows(1)) {
    closed_here = objective.evaluate(start);
    start_known = true;
  }
  // The start's closure, its Jacobian and one trial step: less cannot move x.
  const int first_step_sims = (start_known ? 0 : 1) + objective.jacobianSims(start) + 1;
  if (!objective.budgetAllows(first_step_sims)) {
    // The start's closure, when run here, is the fit's last: convergence.csv gets its row.
    if (closed_here)
      objective.recordIteration("ceres", 0, closed_here->ok() ? closed_here->cost : NAN,
                                closed_here->ok() ? closed_here->mean_deviation_mm : NAN);
    return {{"budget of " + counted(objective.maxSims(), "forward run") +
                 " is below one Jacobian and a step (" + std::to_string(first_step_sims) +
                 " runs, " + std::to_string(objective.maxSims() - objective.forwardSims()) +
                 " left)",
             true}};
  }

  ceres::Problem problem;
  problem.AddParameterBlock(x.data(), n);
  for (int p = 0; p < n; ++p) {
    problem.SetParameterLowerBound(x.data(), p, parameters.lower()(p));
    problem.SetParameterUpperBound(x.data(), p, parameters.upper()(p));
  }
  // The problem owns cost and loss functions (one loss object per block: no shared
  // ownership to get wrong).
  for (int i = 0; i < residual.dataCount(); ++i) {
    // Tracing points through Huber's loss; the section residuals carry their own cap.
    ceres::LossFunction* loss = i < residual.pointCount()
                                    ? new ceres::HuberLoss(residual.options().huber_delta_mm)
                                    : nullptr;
    problem.AddResidualBlock(new DataPointCost(objective, i), loss, x.data());
  }
  if (residual.regularisationCount() > 0) {
    problem.AddResidualBlock(new RegularisationCost(residual), nullptr, x.data());
  }

  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = ceres::DENSE_QR;
  options.num_threads = 1;
  options.max_num_iterations = settings.max_iterations;
  options.function_tolerance = settings.function_tolerance;
  options.parameter_tolerance = settings.parameter_tolerance;
  options.gradient_tolerance = 1e-10;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  options.update_state_every_iteration = true;
  // A cautious first step: Ceres' default (1e4, nearly Gauss-Newton) jumps to the bounds,
  // where closures diverge or crawl to the step cap.
  options.initial_trust_region_radius = settings.initial_trust_region_radius;
  // With bounds Ceres by default runs a line search along the projected step, which asks for
  // Jacobians (2P closures each) at trial points; one Jacobian per accepted step is enough.
  options.max_num_line_search_step_size_iterations = 0;
  ProgressAndBudget callback(objective, x, settings.warm_rejections_before_full);
  options.callbacks.push_back(&callback);

  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  // The solve can end inside Ceres, before the iteration callback, on an accepted trial: one
  // whose Jacobian the budget refused, or whose step met a tolerance. Record the point returned
  // when no row holds it, or convergence.csv would miss the result (and the history would credit
  // the next stage, the slack release, with its drop).
  const std::vector<IterationRecord>& history = objective.history();
  if (objective.best() &&
      std::none_of(history.begin(), history.end(),
                   [&](const IterationRecord& r) { return r.cost == objective.best()->cost; }))
    objective.recordIteration("ceres", static_cast<int>(summary.iterations.size()),
                              objective.best()->cost, objective.best()->mean_deviation_mm);
  // It can also end on a trial it rejects (a step under the parameter tolerance): that closure
  // was run and counted, but no row said so, and convergence.csv's last forward_sims fell one
  // short of metrics.json's. A row for the closure run last closes the count (numbered after
  // this solve's iterations, as the row above, which it never joins: that one takes the count).
  if (!history.empty() && objective.forwardSims() > history.back().forward_sims) {
    const auto last = objective.latest();
    const bool failed = !last || !last->ok();
    objective.recordIteration("ceres", static_cast<int>(summary.iterations.size()),
                              failed ? NAN : last->cost, failed ? NAN : last->mean_deviation_mm);
  }
  if (callback.budget_reached || objective.budgetRefused()) {
    const int refused = objective.refusedJacobianSims();
    // With closures left but too few for the next Jacobian, the budget is not "reached".
    return {{"budget of " + counted(objective.maxSims(), "forward run") + " " +
                 (refused > 0
                      ? "too small for the Jacobian at the last accepted step (it needs " +
                            std::to_string(refused) + " runs, " +
                            std::to_string(objective.maxSims() - objective.forwardSims()) + " left)"
                      : std::string("reached")),
             true}};
  }
  if (callback.warm_distrusted) {
    return {{std::to_string(settings.warm_rejections_before_full) +
             " steps in a row rejected on warm-started differences"},
            true};
  }
  return {{std::string(summary.termination_type == ceres::CONVERGENCE      ? "converged: "
                       : summary.termination_type == ceres::NO_CONVERGENCE ? "not converged: "
                                                                           : "stopped: ") +
           summary.message}};
}

}  // namespace

Termination CeresDriver::minimize(FitObjective& objective, const OptimizerSettings& settings) {
  quietCeresLogging();
  if (objective.parameterCount() == 0) return {"nothing to fit (every cord is locked)"};
  SolveResult solve = solveFromStart(objective, settings);
  if (!solve.warm_distrusted) return solve.termination;
  // The warm-started Jacobian mispredicted step after step: go on from the best point with
  // full-closure differences, recorded as their own stage.
  if (!objective.best()) return solve.termination;  // the callback switches only from a best
  objective.useFullClosureDifferences();
  objective.restartAt(objective.best()->x);
  objective.setStageLabel(name() + "-full");
  SolveResult full = solveFromStart(objective, settings);
  objective.setStageLabel("");
  full.termination.message = solve.termination.message +
                             "; full closures from the best point: " + full.termination.message;
  return full.termination;
}

}  // namespace chordfit::inverse
