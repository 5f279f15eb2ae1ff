#include "inverse/fit_objective.h"

#include <algorithm>

#include <utility>

namespace chordfit::inverse {

namespace {
constexpr std::size_t kCacheSize = 16;
}

FitObjective::FitObjective(const ForwardResidual& residual, const FiniteDifferenceOptions& fd,
                           int max_sims, int sims_before, Clock::time_point start,
                           std::function<void(const IterationRecord&)> on_iteration)
    : residual_(residual),
      fd_(fd),
      start_x_(residual.parameters().initial()),
      max_sims_(max_sims),
      sims_(sims_before),
      start_(start),
      on_iteration_(std::move(on_iteration)) {}

double FitObjective::elapsedSeconds() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

FitObjective::Entry* FitObjective::find(const Eigen::VectorXd& x) {
  for (Entry& entry : cache_) {
    // Exact comparison: the cache must never hand out a neighbouring point's closure.
    if (entry.evaluation->x.size() == x.size() && entry.evaluation->x == x) return &entry;
  }
  return nullptr;
}

std::shared_ptr<const ForwardEvaluation> FitObjective::evaluate(const Eigen::VectorXd& x) {
  if (Entry* entry = find(x)) return entry->evaluation;
  if (!budgetAllows(1)) {
    budget_refused_ = true;
    auto refused = std::make_shared<ForwardEvaluation>();
    refused->x = x;
    refused->error = "forward-run budget exhausted";
    return refused;
  }
  auto evaluation = std::make_shared<const ForwardEvaluation>(residual_.evaluate(x));
  ++sims_;
  if (evaluation->ok() && (!best_ || evaluation->cost < best_->cost)) best_ = evaluation;
  cache_.push_back({evaluation, nullptr});
  if (cache_.size() > kCacheSize) cache_.pop_front();
  return evaluation;
}

std::shared_ptr<const Eigen::MatrixXd> FitObjective::jacobian(const Eigen::VectorXd& x,
                                                              std::string& error) {
  const auto base = evaluate(x);
  if (!base->ok()) {
    error = base->error;
    return nullptr;
  }
  Entry* entry = find(x);
  if (entry->jacobian) return entry->jacobian;
  if (!budgetAllows(jacobianSims(x))) {
    budget_refused_ = true;
    refused_jacobian_sims_ = jacobianSims(x);
    error = "forward-run budget exhausted";
    return nullptr;
  }
  FiniteDifferenceOptions fd = fd_;
  fd.on_closure = closureHeartbeat(progress_, "jacobian");
  JacobianResult result = centralDifferenceJacobian(residual_, x, base->closed_V, fd);
  sims_ += result.forward_sims;
  if (!result.ok()) {
    error = result.error;
    return nullptr;
  }
  entry->jacobian = std::make_shared<const Eigen::MatrixXd>(std::move(result.J));
  return entry->jacobian;
}

int FitObjective::jacobianSims(const Eigen::VectorXd& x) {
  const auto base = cached(x);
  if (!base || !base->ok()) return jacobianSims();
  const std::vector<bool> slack =
      slackParameters(residual_.parameters(), residual_.cordInsertions(), x, base->closed_V, fd_);
  return 2 * static_cast<int>(std::count(slack.begin(), slack.end(), false));
}

void FitObjective::useFullClosureDifferences() {
  fd_.warm_start = false;
  for (Entry& entry : cache_) entry.jacobian = nullptr;
}

void FitObjective::remember(const ForwardEvaluation& evaluation) {
  auto shared = std::make_shared<const ForwardEvaluation>(evaluation);
  if (shared->ok() && (!best_ || shared->cost < best_->cost)) best_ = shared;
  cache_.push_back({shared, nullptr});
  if (cache_.size() > kCacheSize) cache_.pop_front();
}

std::shared_ptr<const ForwardEvaluation> FitObjective::cached(const Eigen::VectorXd& x) {
  Entry* entry = find(x);
  return entry ? entry->evaluation : nullptr;
}

std::shared_ptr<const Eigen::MatrixXd> FitObjective::cachedJacobian(const Eigen::VectorXd& x) {
  Entry* entry = find(x);
  return entry ? entry->jacobian : nullptr;
}

void FitObjective::recordIteration(const std::string& stage, int iteration, double cost,
                                   double mean_deviation_mm) {
  IterationRecord record;
  record.stage = stage_label_.empty() ? stage : stage_label_;
  record.iteration = iteration;
  record.cost = cost;
  record.best_cost = best_ ? best_->cost : cost;
  record.mean_deviation_mm = mean_deviation_mm;
  record.forward_sims = sims_;
  record.elapsed_s = elapsedSeconds();
  history_.push_back(record);
  if (on_iteration_) on_iteration_(record);
}

}  // namespace chordfit::inverse
