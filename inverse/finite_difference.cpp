#include "inverse/finite_difference.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <vector>

namespace chordfit::inverse {

namespace {

double stepOf(const FitParameterization& parameters, int p,
              const FiniteDifferenceOptions& options) {
  return parameters.isScale(p) ? options.scale_step : options.tip_step_mm;
}

bool sameTip(const PmTip& a, const PmTip& b) {
  return a.position == b.position && a.closed_position == b.closed_position;
}

// True when every cord that `perturbed` changes against `base` (rest length or tip) is slack
// at `closed` by more than `margin`.
bool onlySlackCordsChange(const CordSet& base, const CordSet& perturbed,
                          const std::vector<CordInsertionWeights>& insertions,
                          const Eigen::MatrixXd& closed, double margin) {
  const Eigen::VectorXd spans = closedSpans(perturbed, insertions, closed);
  for (std::size_t c = 0; c < perturbed.cords.size(); ++c) {
    const Cord& now = perturbed.cords[c];
    const Cord& before = base.cords[c];
    const bool changed = now.rest_length != before.rest_length ||
                         !sameTip(perturbed.tips[now.tip], base.tips[before.tip]);
    if (changed && !(spans(static_cast<Eigen::Index>(c)) < now.rest_length - margin)) return false;
  }
  return true;
}

}  // namespace

std::vector<bool> slackParameters(const FitParameterization& parameters,
                                  const std::vector<CordInsertionWeights>& insertions,
                                  const Eigen::VectorXd& x, const Eigen::MatrixXd& base_closed,
                                  const FiniteDifferenceOptions& options) {
  const int n = static_cast<int>(x.size());
  std::vector<bool> slack(n, false);
  if (!options.skip_slack || base_closed.rows() == 0) return slack;
  const CordSet base = parameters.apply(x);
  for (int p = 0; p < n; ++p) {
    bool all = true;
    for (double sign : {1.0, -1.0}) {
      Eigen::VectorXd xp = x;
      xp(p) += sign * stepOf(parameters, p, options);
      all = all && onlySlackCordsChange(base, parameters.apply(xp), insertions, base_closed,
                                        options.slack_margin_mm);
    }
    slack[p] = all;
  }
  return slack;
}

namespace {

// The shared part of the heartbeats: a line through `say` at most every `every_s` seconds,
// `line` making it from the seconds since the start (under the lock).
std::function<void(int, int)> heartbeat(
    std::function<void(const std::string&)> say, double every_s,
    std::function<std::string(int done, int total, int calls, double seconds)> line) {
  if (!say) return nullptr;
  struct State {
    std::mutex mutex;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    double said_at_s = 0.0;  // seconds after start of the last line (0: none yet)
    int calls = 0;
  };
  auto state = std::make_shared<State>();
  return [state, say = std::move(say), every_s, line = std::move(line)](int done, int total) {
    const std::lock_guard<std::mutex> lock(state->mutex);
    ++state->calls;
    const double now_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - state->start).count();
    if (now_s - state->said_at_s < every_s) return;
    const std::string text = line(done, total, state->calls, now_s);
    if (text.empty()) return;
    state->said_at_s = now_s;
    say(text);
  };
}

}  // namespace

std::function<void(int, int)> closureHeartbeat(std::function<void(const std::string&)> say,
                                               std::string what, double every_s) {
  return heartbeat(std::move(say), every_s,
                   [what = std::move(what)](int done, int total, int, double seconds) {
                     // Not for the last: the stage's own line follows at once.
                     if (done == total) return std::string();
                     char text[160];
                     std::snprintf(text, sizeof text, "%s: %d of %d closures, %.0f s", what.c_str(),
                                   done, total, seconds);
                     return std::string(text);
                   });
}

std::function<void(int, int)> stageHeartbeat(std::function<void(const std::string&)> say,
                                             std::string what, double every_s) {
  return heartbeat(std::move(say), every_s,
                   [what = std::move(what)](int, int, int calls, double seconds) {
                     char text[160];
                     std::snprintf(text, sizeof text, "%s: %d closures so far, %.0f s",
                                   what.c_str(), calls, seconds);
                     return std::string(text);
                   });
}

JacobianResult centralDifferenceJacobian(const ForwardResidual& residual, const Eigen::VectorXd& x,
                                         const Eigen::MatrixXd& base_closed,
                                         const FiniteDifferenceOptions& options) {
  const int n = static_cast<int>(x.size());
  const FitParameterization& parameters = residual.parameters();
  const std::vector<bool> slack =
      slackParameters(parameters, residual.cordInsertions(), x, base_closed, options);
  std::vector<int> simulated;  // parameters whose columns need closures
  for (int p = 0; p < n; ++p)
    if (!slack[p]) simulated.push_back(p);
  const int m = static_cast<int>(simulated.size());
  std::vector<Eigen::VectorXd> sides(2 * m);
  std::vector<std::string> errors(2 * m);
  const Eigen::MatrixXd* start = options.warm_start ? &base_closed : nullptr;
  auto step = [&](int p) { return stepOf(parameters, p, options); };
  std::atomic<int> done{0};
  parallelFor(2 * m, options.threads, [&](int task) {
    const int p = simulated[task / 2];
    Eigen::VectorXd xp = x;
    xp(p) += (task % 2 == 0 ? 1.0 : -1.0) * step(p);
    ForwardEvaluation e = residual.evaluate(xp, start);
    if (options.on_closure) options.on_closure(++done, 2 * m);
    if (!e.ok()) {
      errors[task] = parameters.names()[p] + ": " + e.error;
      return;
    }
    sides[task] = std::move(e.data);
  });
  JacobianResult result;
  result.forward_sims = 2 * m;
  result.slack_parameters = n - m;
  for (const std::string& e : errors) {
    if (!e.empty()) {
      result.error = e;
      return result;
    }
  }
  result.J = Eigen::MatrixXd::Zero(residual.dataCount(), n);
  for (int k = 0; k < m; ++k) {
    const int p = simulated[k];
    result.J.col(p) = (sides[2 * k] - sides[2 * k + 1]) / (2.0 * step(p));
  }
  return result;
}

}  // namespace chordfit::inverse
