// Zero Jacobian columns for parameters that move only slack cords (inverse/finite_difference.h):
// which parameters qualify, that their columns are exactly 0 without closures where closures
// would give only the solver's noise, and that every other column is unchanged.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/cordset.h"
#include "inverse/finite_difference.h"
#include "inverse/fit_objective.h"
#include "inverse/fit_parameters.h"
#include "inverse/forward_residual.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

// The small case closed with its heuristic cords (rest lengths at the heuristic's upper bound,
// so many hang slack) and traced there, with its per-cord scales and their residual.
struct SlackSetUp {
  testing::TracedSeedClosure seed = testing::tracedSeedClosure("small-normal", 3);
  inverse::FitParameterization scales{seed.traced, *seed.traced.cords,
                                      inverse::ParameterMode::kScales, inverse::ParameterBounds{}};
  inverse::ForwardResidual residual{seed.traced, scales, seed.settings, inverse::ResidualOptions{}};
};

const SlackSetUp& setUp() {
  static const SlackSetUp s;
  return s;
}

TEST(SlackJacobian, ParametersOfCordsSlackBeyondTheStepAndMarginAreSlack) {
  const testing::TracedSeedClosure& seed = setUp().seed;
  const inverse::FitParameterization& parameters = setUp().scales;
  const inverse::FiniteDifferenceOptions options;
  const Eigen::VectorXd x = parameters.initial();
  const std::vector<bool> slack = inverse::slackParameters(
      parameters, setUp().residual.cordInsertions(), x, seed.closed_V, options);
  const CordSet cords = parameters.apply(x);
  const Eigen::VectorXd spans =
      closedSpans(cords, setUp().residual.cordInsertions(), seed.closed_V);
  int slack_count = 0;
  for (std::size_t c = 0; c < cords.cords.size(); ++c) {
    const int p = parameters.cordParameter()[c];
    ASSERT_GE(p, 0);
    // The shorter perturbation, rest (s - h) / s, must still be slack by the margin.
    const double shortest = cords.cords[c].rest_length * (x(p) - options.scale_step) / x(p);
    EXPECT_EQ(slack[p], spans(c) < shortest - options.slack_margin_mm) << "cord " << c;
    slack_count += slack[p];
  }
  // The set-up must have both kinds, or the test says nothing.
  EXPECT_GT(slack_count, 0);
  EXPECT_LT(slack_count, parameters.size());

  inverse::FiniteDifferenceOptions off = options;
  off.skip_slack = false;
  const std::vector<bool> none = inverse::slackParameters(
      parameters, setUp().residual.cordInsertions(), x, seed.closed_V, off);
  EXPECT_EQ(std::count(none.begin(), none.end(), true), 0);
}

TEST(SlackJacobian, ATipIsSlackOnlyWhenAllItsCordsStaySlackAsItMoves) {
  const testing::TracedSeedClosure& seed = setUp().seed;
  CordSet start = *seed.traced.cords;
  // Tip 0's cords lengthened far beyond their spans; tip 1's left as they are.
  for (Cord& cord : start.cords)
    if (cord.tip == 0) cord.rest_length = 1.4 * cord.seed_rest_length;
  const inverse::FitParameterization parameters(
      seed.traced, start, inverse::ParameterMode::kScalesAndTips, inverse::ParameterBounds{});
  const Eigen::VectorXd x = parameters.initial();
  const Eigen::VectorXd spans =
      closedSpans(parameters.apply(x), setUp().residual.cordInsertions(), seed.closed_V);
  bool tip1_has_taut = false;
  for (std::size_t c = 0; c < start.cords.size(); ++c) {
    if (start.cords[c].tip == 0) {
      ASSERT_LT(spans(c), start.cords[c].rest_length - 1.0);
    } else {
      tip1_has_taut |= spans(c) > start.cords[c].rest_length - 0.5;
    }
  }
  ASSERT_TRUE(tip1_has_taut);
  const std::vector<bool> slack =
      inverse::slackParameters(parameters, setUp().residual.cordInsertions(), x, seed.closed_V,
                               inverse::FiniteDifferenceOptions{});
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(slack[parameters.tipParameter(0) + k]) << "tip 0 coordinate " << k;
    EXPECT_FALSE(slack[parameters.tipParameter(1) + k]) << "tip 1 coordinate " << k;
  }
}

TEST(SlackJacobian, SlackColumnsAreZeroWithoutClosuresAndTheOthersUnchanged) {
  const testing::TracedSeedClosure& seed = setUp().seed;
  const inverse::FitParameterization& parameters = setUp().scales;
  const inverse::ForwardResidual& residual = setUp().residual;
  const Eigen::VectorXd x = parameters.initial();
  inverse::FiniteDifferenceOptions skip;
  skip.warm_start = true;
  inverse::FiniteDifferenceOptions all = skip;
  all.skip_slack = false;
  const std::vector<bool> slack = inverse::slackParameters(
      parameters, setUp().residual.cordInsertions(), x, seed.closed_V, skip);
  const int slack_count = static_cast<int>(std::count(slack.begin(), slack.end(), true));

  const inverse::JacobianResult skipped =
      inverse::centralDifferenceJacobian(residual, x, seed.closed_V, skip);
  const inverse::JacobianResult closed =
      inverse::centralDifferenceJacobian(residual, x, seed.closed_V, all);
  ASSERT_TRUE(skipped.ok()) << skipped.error;
  ASSERT_TRUE(closed.ok()) << closed.error;
  EXPECT_EQ(skipped.slack_parameters, slack_count);
  EXPECT_EQ(skipped.forward_sims, 2 * (parameters.size() - slack_count));
  EXPECT_EQ(closed.forward_sims, 2 * parameters.size());

  double taut_scale = 0.0;  // largest entry of a column that moves a taut cord
  for (int p = 0; p < parameters.size(); ++p)
    if (!slack[p]) taut_scale = std::max(taut_scale, closed.J.col(p).cwiseAbs().maxCoeff());
  ASSERT_GT(taut_scale, 1.0);  // mm per unit scale: the data see the taut cords
  for (int p = 0; p < parameters.size(); ++p) {
    if (slack[p]) {
      EXPECT_EQ(skipped.J.col(p).cwiseAbs().maxCoeff(), 0.0) << parameters.names()[p];
      // What the closures would have said: nothing but the solver's noise.
      EXPECT_LT(closed.J.col(p).cwiseAbs().maxCoeff(), 1e-3 * taut_scale) << parameters.names()[p];
    } else {
      EXPECT_TRUE(skipped.J.col(p) == closed.J.col(p)) << parameters.names()[p];
    }
  }
}

TEST(SlackJacobian, TheObjectiveCountsAndChargesOnlyTheClosuresItRuns) {
  const inverse::FitParameterization& parameters = setUp().scales;
  const inverse::ForwardResidual& residual = setUp().residual;
  inverse::FiniteDifferenceOptions fd;
  fd.warm_start = true;
  inverse::FitObjective objective(residual, fd, 1000, 0, inverse::FitObjective::Clock::now(),
                                  nullptr);
  const Eigen::VectorXd x = parameters.initial();
  // Before x is closed the count is the upper bound, 2 per parameter.
  EXPECT_EQ(objective.jacobianSims(x), 2 * parameters.size());
  const auto base = objective.evaluate(x);
  ASSERT_TRUE(base->ok()) << base->error;
  const std::vector<bool> slack =
      inverse::slackParameters(parameters, residual.cordInsertions(), x, base->closed_V, fd);
  const int taut = static_cast<int>(std::count(slack.begin(), slack.end(), false));
  EXPECT_EQ(objective.jacobianSims(x), 2 * taut);
  ASSERT_LT(taut, parameters.size());

  const int before = objective.forwardSims();
  std::string error;
  ASSERT_NE(objective.jacobian(x, error), nullptr) << error;
  EXPECT_EQ(objective.forwardSims() - before, 2 * taut);
}

}  // namespace
}  // namespace chordfit
