// The inverse fit (inverse/fit_cords.h) on the bundled small case: recovery of perturbed
// cords from noise-free tracings, locks and bounds, every optimiser through the common
// interface, and independence of the thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <set>

#include "core/case_io.h"
#include "core/closure_model.h"
#include "core/metrics.h"
#include "inverse/fit_cords.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

constexpr double kRecoveryTolerance = 0.02;  // issue 5: recovered within 2 %
constexpr double kTrueScale = 0.65;          // every cord taut, as in the cohort's truth
constexpr double kPerturbation = 0.15;       // issue 5: four cords perturbed by +-15 %
constexpr double kNearPlaneMm = 3.0;         // identifiable: attached this near a plane
constexpr int kRecoveryBudget = 200;         // forward closures of the recovery fit

std::filesystem::path smallCase() {
  return std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
}

// The small case with noise-free tracings of a closure in which four identifiable cords are
// perturbed; `base` is the unperturbed set (the fit's seed, every other cord locked).
struct RecoveryProblem {
  ValveCase valve_case;
  SimulationSettings settings;
  CordSet base, truth;
  std::vector<int> perturbed;
};

const RecoveryProblem& recoveryProblem() {
  static const RecoveryProblem problem = [] {
    RecoveryProblem p;
    Diagnostics diagnostics;
    auto loaded = loadCase(smallCase(), diagnostics);
    if (!loaded || !loaded->cords) throw std::runtime_error("bundled case small-normal missing");
    p.valve_case = *loaded;
    p.settings = settingsFromJson(p.valve_case.simulation_json, diagnostics);
    p.base = *p.valve_case.cords;
    for (Cord& cord : p.base.cords) cord.rest_length = cord.seed_rest_length * kTrueScale;
    const SimulationResult closed = simulateClosure(p.valve_case, p.base, p.settings);
    if (!closed.ok()) throw std::runtime_error(closed.error);
    // Identifiable: taut in the closed state and attached near a tracing plane; take the four
    // tautest, so the choice is deterministic.
    std::vector<std::pair<double, int>> candidates;
    for (std::size_t c = 0; c < p.base.cords.size(); ++c) {
      const Eigen::Vector3d v = closed.V.row(p.base.cords[c].vertex).transpose();
      double nearest = INFINITY;
      for (const Tracing& t : p.valve_case.tracings) {
        nearest = std::min(nearest, std::abs(t.plane_normal.dot(v - t.plane_origin)));
      }
      if (closed.cord_force(c) > 0.0 && nearest < kNearPlaneMm) {
        candidates.push_back({-closed.cord_force(c), static_cast<int>(c)});
      }
    }
    std::sort(candidates.begin(), candidates.end());
    // One cord per group (leaflet x tip): perturbed neighbours would trade off against each
    // other (a lengthened cord next to a shortened one may hang slack at the seed).
    {
      const std::vector<std::string> groups = inverse::cordGroups(p.valve_case, p.base);
      std::vector<std::pair<double, int>> spread;
      std::set<std::string> used;
      for (const auto& candidate : candidates) {
        if (used.insert(groups[candidate.second]).second) spread.push_back(candidate);
      }
      for (const auto& candidate : candidates) {
        if (std::find(spread.begin(), spread.end(), candidate) == spread.end()) {
          spread.push_back(candidate);
        }
      }
      candidates = spread;
    }
    // Lengthen each by 15 %; a cord lengthened into slackness would be unidentifiable (every
    // longer length closes the same), so such a cord is shortened by 15 % instead, and a cord
    // slack even then is replaced by the next candidate.
    SimulationResult truth;
    std::size_t next = 0;
    std::vector<double> factors;
    while (p.perturbed.size() < 4 || !truth.ok()) {
      while (p.perturbed.size() < 4 && next < candidates.size()) {
        p.perturbed.push_back(candidates[next++].second);
        factors.push_back(1.0 + kPerturbation);
      }
      if (p.perturbed.size() < 4) throw std::runtime_error("fewer than 4 identifiable cords");
      p.truth = p.base;
      for (int k = 0; k < 4; ++k) p.truth.cords[p.perturbed[k]].rest_length *= factors[k];
      truth = simulateClosure(p.valve_case, p.truth, p.settings);
      if (!truth.ok()) throw std::runtime_error(truth.error);
      if (truth.cord_force.size() == 0) throw std::runtime_error("no cord forces");
      bool all_taut = true;
      for (int k = 3; k >= 0; --k) {
        if (truth.cord_force(p.perturbed[k]) > 0.0) continue;
        all_taut = false;
        if (factors[k] > 1.0) {
          factors[k] = 1.0 - kPerturbation;  // shortened instead: stays taut
        } else {
          p.perturbed.erase(p.perturbed.begin() + k);
          factors.erase(factors.begin() + k);
        }
      }
      if (!all_taut) truth.error = "again";
    }
    std::sort(p.perturbed.begin(), p.perturbed.end());
    p.valve_case.tracings = testing::noiseFreeTracings(p.valve_case, truth.V, 3);  // 3 as bundled
    for (std::size_t c = 0; c < p.base.cords.size(); ++c) {
      if (std::find(p.perturbed.begin(), p.perturbed.end(), static_cast<int>(c)) ==
          p.perturbed.end()) {
        p.base.cords[c].locked = true;
        p.base.cords[c].provenance = Provenance::kManual;
      }
    }
    return p;
  }();
  return problem;
}

inverse::FitOptions perCordOptions(const std::string& optimizer, int max_sims, int threads) {
  inverse::FitOptions options;
  options.mode = inverse::ParameterMode::kScales;
  options.bounds.scale_lower = 0.4;  // the problem's scales (0.65 +- 15 %) lie below 0.7
  options.bounds.scale_upper = 1.5;
  options.prefit.enabled = false;  // the four free cords start at their unperturbed values
  options.segment_prefit.enabled = false;
  options.optimizer = optimizer;
  options.max_sims = max_sims;
  options.finite_difference.threads = threads;
  return options;
}

TEST(InverseFit, RecoversFourPerturbedCordsWithinTwoPercentAndKeepsLockedCords) {
  const RecoveryProblem& p = recoveryProblem();
  // 200 closures: Ceres stops on its tolerance after ~184 with the own-leaflet residual (the
  // whole-mesh distance needed ~110; at 110 own-leaflet ends with one cord 2.5 % off).
  inverse::FitOptions options = perCordOptions("ceres", kRecoveryBudget, 2);
  // Noise-free tracings: the data alone determine the four cords, so the prior is made 10x
  // weaker than the default (which biases a weakly seen cord by ~2 % here toward its seed).
  options.residual.weights.seed *= 0.1;
  options.residual.weights.neighbour *= 0.1;
  const inverse::FitOutcome fit = inverse::fitCords(p.valve_case, p.base, p.settings, options);
  ASSERT_TRUE(fit.ok()) << fit.error;
  ASSERT_EQ(fit.x.size(), 4);
  for (int c : p.perturbed) {
    const double truth = p.truth.cords[c].rest_length;
    EXPECT_NEAR(fit.fitted.cords[c].rest_length / truth, 1.0, kRecoveryTolerance)
        << "cord " << c << ": seed " << p.base.cords[c].rest_length << ", truth " << truth
        << ", fitted " << fit.fitted.cords[c].rest_length << " (" << fit.termination << ")";
    EXPECT_EQ(fit.fitted.cords[c].provenance, Provenance::kFitted);
  }
  for (std::size_t c = 0; c < p.base.cords.size(); ++c) {
    if (!p.base.cords[c].locked) continue;
    EXPECT_EQ(fit.fitted.cords[c].rest_length, p.base.cords[c].rest_length) << "cord " << c;
    EXPECT_EQ(fit.fitted.cords[c].provenance, Provenance::kManual);
  }
  EXPECT_LT(fit.final_evaluation.mean_deviation_mm, 0.2 * fit.seed_evaluation.mean_deviation_mm);
  EXPECT_LE(fit.forward_sims, kRecoveryBudget);
}

// The start (every scale 0.65) lies inside the bounds, so the checks that the scales stay
// within them would pass a fit that did nothing: each perturbed cord must also move towards the
// truth outside the bounds. The two shortened cords (truth 0.5525) end at the lower bound 0.62.
// The two lengthened ones (truth 0.7475) move up but need not reach 0.68: with the shortened
// cords held at 0.62 their best lengths lie inside (measured 0.6762 and 0.6672; a fit started
// at the corner 0.68 moves the second back to 0.663, at a lower cost than the corner's).
TEST(InverseFit, KeepsEveryScaleWithinItsBounds) {
  const RecoveryProblem& p = recoveryProblem();
  inverse::FitOptions options = perCordOptions("ceres", 40, 2);
  options.bounds.scale_lower = 0.62;  // the cords perturbed upward want 0.7475: held at 0.68
  options.bounds.scale_upper = 0.68;
  const inverse::FitOutcome fit = inverse::fitCords(p.valve_case, p.base, p.settings, options);
  ASSERT_TRUE(fit.ok()) << fit.error;
  int shortened = 0, lengthened = 0;
  for (int c : p.perturbed) {
    const double scale = fit.fitted.cords[c].scale();
    EXPECT_GE(scale, 0.62 - 1e-12) << "cord " << c;
    EXPECT_LE(scale, 0.68 + 1e-12) << "cord " << c;
    if (p.truth.cords[c].scale() < 0.62) {
      ++shortened;
      EXPECT_NEAR(scale, 0.62, 1e-3) << "cord " << c << " (truth below the lower bound)";
    } else {
      ASSERT_GT(p.truth.cords[c].scale(), 0.68) << "cord " << c;
      ++lengthened;
      EXPECT_GT(scale, 0.66) << "cord " << c << " (truth above the upper bound, start 0.65)";
    }
  }
  EXPECT_GT(shortened, 0);
  EXPECT_GT(lengthened, 0);
  EXPECT_LT(fit.final_evaluation.cost, fit.seed_evaluation.cost);
}

TEST(InverseFit, EveryOptimizerRunsThroughTheCommonInterfaceWithinItsBudget) {
  const RecoveryProblem& p = recoveryProblem();
  for (const std::string& name : inverse::optimizerNames()) {
    // seed + one Ceres Jacobian (8) + a trial point + the slack release's closure
    constexpr int kBudget = 11;
    const inverse::FitOutcome fit =
        inverse::fitCords(p.valve_case, p.base, p.settings, perCordOptions(name, kBudget, 2));
    ASSERT_TRUE(fit.ok()) << name << ": " << fit.error;
    EXPECT_LE(fit.forward_sims, kBudget) << name;
    EXPECT_GE(fit.history.size(), 2u) << name << ": no iteration recorded";
    EXPECT_LE(fit.final_evaluation.cost, fit.seed_evaluation.cost) << name;
    EXPECT_FALSE(fit.termination.empty()) << name;
    // Every optimiser keeps the seed's locked cords bit for bit.
    for (std::size_t c = 0; c < p.base.cords.size(); ++c) {
      if (!p.base.cords[c].locked) continue;
      EXPECT_EQ(fit.fitted.cords[c].rest_length, p.base.cords[c].rest_length) << name << " " << c;
      EXPECT_TRUE(fit.fitted.cords[c].locked) << name << " " << c;
    }
  }
}

// 14 closures: the seed, a Jacobian (8) and 4 left, fewer than the next Jacobian needs, and one
// kept for the slack release. The 4 go to trial steps from the first Jacobian (an accepted one
// is kept as the best point seen) instead of being left unused.
TEST(InverseFit, SpendsWhatIsLeftAfterItsLastJacobianOnTrialSteps) {
  const RecoveryProblem& p = recoveryProblem();
  const inverse::FitOutcome fit =
      inverse::fitCords(p.valve_case, p.base, p.settings, perCordOptions("ceres", 14, 2));
  ASSERT_TRUE(fit.ok()) << fit.error;
  const int release = fit.slack_release.proposal.empty() ? 0 : 1;
  EXPECT_GE(fit.forward_sims - release, 10) << "no trial step after the first Jacobian";
  EXPECT_LE(fit.forward_sims, 14);
  EXPECT_LT(fit.final_evaluation.cost, fit.seed_evaluation.cost);
  EXPECT_NE(fit.termination.find(
                "budget of 13 forward runs too small for the Jacobian at the last accepted step"),
            std::string::npos)
      << fit.termination;
}

TEST(InverseFit, GivesBitIdenticalResultsWithOneAndTwoThreads) {
  const RecoveryProblem& p = recoveryProblem();
  const inverse::FitOutcome one =
      inverse::fitCords(p.valve_case, p.base, p.settings, perCordOptions("ceres", 20, 1));
  const inverse::FitOutcome two =
      inverse::fitCords(p.valve_case, p.base, p.settings, perCordOptions("ceres", 20, 2));
  ASSERT_TRUE(one.ok() && two.ok());
  EXPECT_EQ(one.forward_sims, two.forward_sims);
  ASSERT_EQ(one.x.size(), two.x.size());
  for (Eigen::Index i = 0; i < one.x.size(); ++i) EXPECT_EQ(one.x(i), two.x(i)) << i;
  EXPECT_EQ(one.final_evaluation.cost, two.final_evaluation.cost);
}

// The user locked every cord, one of them at a wrong length (a perturbed cord at its unperturbed
// value, against tracings of the truth): the probe (inverse/locked_cord_probe.h) must single it
// out and move it toward its true length, skip a slack cord, and give the same numbers on one
// thread or two.
TEST(InverseFit, LockedCordProbeFindsTheLockThatHoldsTheFitBack) {
  const RecoveryProblem& p = recoveryProblem();
  const inverse::ParameterBounds bounds = perCordOptions("ceres", 1, 1).bounds;
  for (int wrong : p.perturbed) {
    CordSet locked = p.truth;
    for (Cord& cord : locked.cords) {
      cord.locked = true;
      cord.provenance = Provenance::kManual;
    }
    locked.cords[wrong].rest_length = p.base.cords[wrong].rest_length;
    // One other cord far too long: slack, so not probed.
    const int slack_cord = wrong == 0 ? 1 : 0;
    locked.cords[slack_cord].rest_length *= 1.5;
    const inverse::FitParameterization parameters(p.valve_case, locked,
                                                  inverse::ParameterMode::kScales, bounds);
    ASSERT_EQ(parameters.size(), 0);
    const inverse::ForwardResidual residual(p.valve_case, parameters, p.settings, {});
    const inverse::ForwardEvaluation fitted = inverse::closeForData(p.valve_case, locked, residual);
    ASSERT_TRUE(fitted.ok()) << fitted.error;
    const Eigen::VectorXd spans = closedSpans(locked, residual.cordInsertions(), fitted.closed_V);
    auto probe = [&](int threads) {
      inverse::LockedCordProbeOptions options;
      options.threads = threads;
      return inverse::probeLockedCords(p.valve_case, locked, fitted, spans, residual, bounds,
                                       options);
    };
    const inverse::LockedCordProbes two = probe(2);
    ASSERT_EQ(two.cords.size(), locked.cords.size());
    EXPECT_TRUE(two.cords[slack_cord].slack) << "cord " << slack_cord;
    EXPECT_TRUE(two.cords[slack_cord].trial.cords.empty()) << "a slack cord is not probed";
    int taut = 0;
    for (const inverse::LockedCordProbe& c : two.cords) taut += c.slack ? 0 : 1;
    EXPECT_EQ(two.forward_sims, 3 * taut + static_cast<int>(two.segments.size()));

    const inverse::LockedCordTrial& trial = two.cords[wrong].trial;
    ASSERT_TRUE(trial.ok()) << "cord " << wrong << ": " << trial.error;
    EXPECT_LT(trial.data_cost, 0.5 * two.fit_data_cost) << "cord " << wrong;
    const double toward = p.truth.cords[wrong].rest_length - locked.cords[wrong].rest_length;
    EXPECT_GT((trial.lengths_mm[0] - locked.cords[wrong].rest_length) * toward, 0.0)
        << "cord " << wrong << " moved away from its true length";
    // No other cord alone explains the tracings as well.
    for (std::size_t c = 0; c < two.cords.size(); ++c) {
      if (static_cast<int>(c) == wrong || !two.cords[c].trial.ok()) continue;
      EXPECT_GT(two.cords[c].trial.data_cost, trial.data_cost) << "cord " << c << " vs " << wrong;
    }
    const inverse::LockedCordTrial* best = two.best();
    ASSERT_NE(best, nullptr);
    EXPECT_NE(std::find(best->cords.begin(), best->cords.end(), wrong), best->cords.end());

    if (wrong != p.perturbed.front()) continue;
    const inverse::LockedCordProbes one = probe(1);
    ASSERT_EQ(one.segments.size(), two.segments.size());
    for (std::size_t c = 0; c < one.cords.size(); ++c) {
      EXPECT_EQ(one.cords[c].trial.lengths_mm, two.cords[c].trial.lengths_mm) << c;
      EXPECT_EQ(one.cords[c].trial.data_cost, two.cords[c].trial.data_cost) << c;
    }
    for (std::size_t s = 0; s < one.segments.size(); ++s)
      EXPECT_EQ(one.segments[s].trial.data_cost, two.segments[s].trial.data_cost) << s;
  }
}

// fit's note on an early stop (a relative cost change met far from a minimum) is for NLopt's
// local derivative-free methods; Ceres and the global crs2 stop otherwise.
TEST(InverseFit, TheLocalDerivativeFreeDriversSayWhatTheyAre) {
  for (const std::string& name : inverse::optimizerNames()) {
    const auto driver = inverse::makeOptimizer(name);
    ASSERT_TRUE(driver) << name;
    EXPECT_EQ(driver->localDerivativeFree(),
              name == "bobyqa" || name == "cobyla" || name == "sbplx")
        << name;
  }
}

TEST(InverseFit, RejectsAnUnknownOptimizer) {
  const RecoveryProblem& p = recoveryProblem();
  const inverse::FitOutcome fit =
      inverse::fitCords(p.valve_case, p.base, p.settings, perCordOptions("newton", 5, 1));
  EXPECT_FALSE(fit.ok());
  EXPECT_NE(fit.error.find("newton"), std::string::npos);
}

}  // namespace
}  // namespace chordfit
