#include "inverse/locked_cord_probe.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include <Eigen/Cholesky>

#include "core/metrics.h"
#include "inverse/global_prefit.h"
#include "inverse/robust_loss.h"

namespace chordfit::inverse {

const LockedCordTrial* LockedCordProbes::best() const {
  const LockedCordTrial* best = nullptr;
  auto consider = [&](const LockedCordTrial& trial) {
    if (!trial.ok() || !(trial.data_cost < fit_data_cost)) return;
    if (!best || trial.data_cost < best->data_cost) best = &trial;
  };
  for (const LockedCordProbe& probe : cords) consider(probe.trial);
  for (const LockedSegmentProbe& probe : segments) consider(probe.trial);
  return best;
}

namespace {

CordSet withRestLengths(const CordSet& cords, const LockedCordTrial& trial) {
  CordSet changed = cords;
  for (std::size_t k = 0; k < trial.cords.size(); ++k)
    changed.cords[trial.cords[k]].rest_length = trial.lengths_mm[k];
  return changed;
}

// The probe's length: l (1 + delta), |delta| <= max_change, its scale within the fit's
// bounds widened to the cord's own scale (a cord the user locked outside them).
double probeLength(const Cord& cord, double delta, const ParameterBounds& bounds,
                   double max_change) {
  double length = cord.rest_length * (1.0 + std::clamp(delta, -max_change, max_change));
  if (cord.seed_rest_length > 0.0) {
    const double scale = cord.scale();
    const double lo = std::min(bounds.scale_lower, scale) * cord.seed_rest_length;
    const double hi = std::max(bounds.scale_upper, scale) * cord.seed_rest_length;
    length = std::clamp(length, lo, hi);
  }
  return length;
}

// The damped Gauss-Newton step of the cords in `columns` (columns of J, d r / d delta) at the
// residuals r with IRLS weights w: the gradient g = J^T W r, the (undamped) Gauss-Newton
// matrix H = J^T W J and delta = -(H + mu I)^-1 g. An empty step when no tracing point moves
// with them.
struct Step {
  Eigen::VectorXd g, delta;
  Eigen::MatrixXd H;
  // The linear model's drop of the data cost for a step d: -(g^T d + 1/2 d^T H d); for the
  // step as applied (capped, bounded), not the one proposed.
  double drop(const Eigen::VectorXd& d) const { return -(g.dot(d) + 0.5 * d.dot(H * d)); }
};

Step gaussNewtonStep(const Eigen::MatrixXd& J, const Eigen::VectorXd& r, const Eigen::VectorXd& w) {
  const Eigen::MatrixXd Jw = w.cwiseSqrt().asDiagonal() * J;
  Step step;
  step.g = J.transpose() * w.cwiseProduct(r);
  step.H = Jw.transpose() * Jw;
  const double trace = step.H.trace();
  if (!(trace > 0.0)) return {};
  Eigen::MatrixXd damped = step.H;
  if (damped.cols() > 1)
    damped.diagonal().array() += 1e-3 * trace / static_cast<double>(damped.cols());
  step.delta = -damped.ldlt().solve(step.g);
  return step;
}

}  // namespace

LockedCordProbes probeLockedCords(const ValveCase& valve_case, const CordSet& fitted,
                                  const ForwardEvaluation& fitted_evaluation,
                                  const Eigen::VectorXd& closed_spans,
                                  const ForwardResidual& residual, const ParameterBounds& bounds,
                                  const LockedCordProbeOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  LockedCordProbes out;
  out.fit_data_cost = residual.cost(fitted_evaluation.data, Eigen::VectorXd());
  out.fit_mean_deviation_mm = fitted_evaluation.mean_deviation_mm;
  out.relative_step = options.relative_step;
  out.max_change = options.max_change;
  std::vector<int> taut;  // indices into out.cords
  for (std::size_t c = 0; c < fitted.cords.size(); ++c) {
    const Cord& cord = fitted.cords[c];
    if (!cord.locked) continue;
    LockedCordProbe probe;
    probe.cord = static_cast<int>(c);
    probe.span_mm = closed_spans(static_cast<Eigen::Index>(c));
    probe.slack = slackAtSpan(probe.span_mm, cord.rest_length);
    if (!probe.slack) taut.push_back(static_cast<int>(out.cords.size()));
    out.cords.push_back(probe);
  }
  if (taut.empty()) return out;
  const int n = static_cast<int>(taut.size());
  // 2 per cord, one trial per cord and one per segment with two or more (at most n / 2).
  const int most = 3 * n + n / 2;
  if (options.on_start) {
    options.on_start("locked cords: probing the " + std::to_string(n) + " taut of " +
                     std::to_string(out.cords.size()) + ", up to " + std::to_string(most) +
                     " closures");
  }

  // Central differences: closures at l (1 - h) and l (1 + h) of each taut locked cord.
  const double h = options.relative_step;
  std::vector<CordSet> side_sets;
  for (int k = 0; k < 2 * n; ++k) {
    const int cord = out.cords[taut[k / 2]].cord;
    LockedCordTrial side;
    side.cords = {cord};
    side.lengths_mm = {fitted.cords[cord].rest_length * (k % 2 == 0 ? 1.0 - h : 1.0 + h)};
    side_sets.push_back(withRestLengths(fitted, side));
  }
  const std::vector<ForwardEvaluation> sides =
      closeCordSets(valve_case, side_sets, residual, options.threads, options.on_closure);
  out.forward_sims += 2 * n;

  const Eigen::VectorXd& r = fitted_evaluation.data;
  const Eigen::VectorXd w =
      huberWeights(r, residual.pointCount(), residual.options().huber_delta_mm);
  Eigen::MatrixXd J(r.size(), n);  // d r / d delta, delta the relative change of a length
  std::vector<bool> differentiated(n, false);
  for (int i = 0; i < n; ++i) {
    const ForwardEvaluation& minus = sides[2 * i];
    const ForwardEvaluation& plus = sides[2 * i + 1];
    if (!minus.ok() || !plus.ok()) {
      out.cords[taut[i]].trial.error =
          "a difference closure failed: " + (minus.ok() ? plus.error : minus.error);
      J.col(i).setZero();
      continue;
    }
    J.col(i) = (plus.data - minus.data) / (2.0 * h);
    differentiated[i] = true;
  }

  // The trials: each differentiated cord alone, then each segment's differentiated cords.
  std::vector<LockedCordTrial*> trials;
  auto propose = [&](LockedCordTrial& trial, const std::vector<int>& columns) {
    Eigen::MatrixXd Jc(J.rows(), static_cast<Eigen::Index>(columns.size()));
    for (std::size_t k = 0; k < columns.size(); ++k) Jc.col(k) = J.col(columns[k]);
    const Step step = gaussNewtonStep(Jc, r, w);
    for (std::size_t k = 0; k < columns.size(); ++k) {
      const int cord = out.cords[taut[columns[k]]].cord;
      trial.cords.push_back(cord);
      trial.lengths_mm.push_back(
          step.delta.size() > 0
              ? probeLength(fitted.cords[cord], step.delta(k), bounds, options.max_change)
              : fitted.cords[cord].rest_length);
    }
    if (step.delta.size() == 0) {  // nothing moves: the fitted closure is the answer
      trial.data_cost = out.fit_data_cost;
      trial.mean_deviation_mm = out.fit_mean_deviation_mm;
      return;
    }
    Eigen::VectorXd applied(static_cast<Eigen::Index>(columns.size()));
    for (std::size_t k = 0; k < columns.size(); ++k)
      applied(k) = trial.lengths_mm[k] / fitted.cords[trial.cords[k]].rest_length - 1.0;
    trial.predicted_drop = out.fit_data_cost > 0.0 ? step.drop(applied) / out.fit_data_cost : 0.0;
    trials.push_back(&trial);
  };
  for (int i = 0; i < n; ++i)
    if (differentiated[i]) propose(out.cords[taut[i]].trial, {i});
  const Eigen::VectorXi segment_of_vertex = openStateSegments(valve_case.mesh);
  std::map<int, std::vector<int>> by_segment;  // segment id -> columns
  for (int i = 0; i < n; ++i)
    if (differentiated[i])
      by_segment[segment_of_vertex(fitted.cords[out.cords[taut[i]].cord].vertex)].push_back(i);
  for (const auto& [segment, columns] : by_segment) {
    if (segment < 0 || columns.size() < 2) continue;
    out.segments.push_back({segment, {}});
  }
  // Pointers into out.segments only after it stops growing.
  for (LockedSegmentProbe& probe : out.segments) propose(probe.trial, by_segment[probe.segment]);

  std::vector<CordSet> trial_sets;
  for (const LockedCordTrial* trial : trials) trial_sets.push_back(withRestLengths(fitted, *trial));
  const std::vector<ForwardEvaluation> trial_closures =
      closeCordSets(valve_case, trial_sets, residual, options.threads, options.on_closure);
  for (std::size_t k = 0; k < trials.size(); ++k) {
    const ForwardEvaluation& e = trial_closures[k];
    if (!e.ok()) {
      trials[k]->error = "the probe's closure failed: " + e.error;
      continue;
    }
    trials[k]->data_cost = e.cost;
    trials[k]->mean_deviation_mm = e.mean_deviation_mm;
  }
  out.forward_sims += static_cast<int>(trials.size());
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace chordfit::inverse
