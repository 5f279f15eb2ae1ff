// The tissue pre-fit (inverse/tissue_prefit.h): from uniform tissue it finds the segment whose
// tissue is softer in the truth, keeps manual and locked cords, and does nothing when off.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <mutex>

#include "core/case_io.h"
#include "core/closure_model.h"
#include "core/cohort_presets.h"
#include "core/metrics.h"
#include "inverse/global_prefit.h"
#include "inverse/tissue_prefit.h"
#include "tests/test_prefit_start.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

constexpr double kBaseScale = 0.8;  // every cord taut, as the cohort's normal cords
constexpr double kSoftP2 = 0.1;     // the truth's P2 tissue factor, on the pre-fit's grid

// valve_case: uniform tissue, tracings of the soft-P2 truth; base: all cords at kBaseScale, one
// locked manual cord in P2.
using TissueProblem = testing::PrefitStart;

const TissueProblem& tissueProblem() {
  static const TissueProblem problem = [] {
    TissueProblem p = testing::smallNormalPrefitStart(kBaseScale);
    for (Cord& cord : p.base.cords) {
      if (p.vertex_segment(cord.vertex) == p.p2) {
        cord.locked = true;
        cord.provenance = Provenance::kManual;
        break;
      }
    }
    ValveCase truth = p.valve_case;
    truth.tissue_stiffness = Eigen::VectorXd::Ones(truth.mesh.V.rows());
    for (Eigen::Index v = 0; v < truth.tissue_stiffness.size(); ++v) {
      if (p.vertex_segment(v) == p.p2) truth.tissue_stiffness(v) = kSoftP2;
    }
    // The truth differs in tissue only: its tracings are drawn on the same mesh and annulus.
    p.valve_case.tracings = testing::tracingsOfTruth(truth, p.base, p.settings, 3);
    return p;
  }();
  return problem;
}

TEST(TissuePrefit, FindsTheSofterP2AndKeepsManualCords) {
  const TissueProblem& p = tissueProblem();
  const inverse::ParameterBounds bounds;
  const inverse::FitParameterization parameters(p.valve_case, p.base,
                                                inverse::ParameterMode::kScales, bounds);
  const inverse::ForwardResidual residual(p.valve_case, parameters, p.settings, {});
  const std::vector<inverse::ForwardEvaluation> start =
      inverse::closeCordSets(p.valve_case, {p.base}, residual, 2);
  ASSERT_TRUE(start[0].ok()) << start[0].error;
  inverse::TissuePrefitOptions options;
  options.enabled = true;
  std::mutex progress_mutex;  // on_closure comes from the worker threads
  int progress_calls = 0;
  int largest_done = 0;
  options.on_closure = [&](int done, int most) {
    const std::lock_guard<std::mutex> lock(progress_mutex);
    ++progress_calls;
    largest_done = std::max(largest_done, done);
    EXPECT_EQ(most, options.closures()) << "the bound the stage announces";
  };
  const inverse::TissuePrefitResult result =
      inverse::segmentTissuePrefit(p.valve_case, p.base, start[0], bounds, residual, options);
  EXPECT_EQ(progress_calls, result.forward_sims) << "one progress call per closure";
  EXPECT_EQ(largest_done, result.forward_sims) << "counted across the rounds";

  // Noise-free tracings of a grid point: the first accepted change is the truth itself.
  ASSERT_FALSE(result.changed.empty());
  EXPECT_EQ(result.changed.front(), "P2 0.1");
  EXPECT_LT(result.best.cost, 1e-9 * start[0].cost);
  ASSERT_EQ(result.tissue.size(), p.valve_case.mesh.V.rows());
  for (Eigen::Index v = 0; v < result.tissue.size(); ++v) {
    if (p.vertex_segment(v) == p.p2) {
      EXPECT_EQ(result.tissue(v), kSoftP2) << "P2 vertex " << v;
    }
  }
  for (std::size_t c = 0; c < p.base.cords.size(); ++c) {
    EXPECT_EQ(result.start.cords[c].rest_length, p.base.cords[c].rest_length) << "cord " << c;
  }
  EXPECT_LE(result.forward_sims, options.closures());
}

TEST(TissuePrefit, DisabledChangesNothing) {
  const TissueProblem& p = tissueProblem();
  inverse::ForwardEvaluation start;
  start.cost = 1.0;
  const inverse::FitParameterization parameters(p.valve_case, p.base,
                                                inverse::ParameterMode::kScales, {});
  const inverse::ForwardResidual residual(p.valve_case, parameters, p.settings, {});
  const inverse::TissuePrefitResult result =
      inverse::segmentTissuePrefit(p.valve_case, p.base, start, {}, residual, {});
  EXPECT_EQ(result.forward_sims, 0);
  EXPECT_TRUE(result.changed.empty());
  EXPECT_EQ(result.tissue.size(), 0);
}

// End to end: `fit --tissue-prefit` writes the tissue it fitted the cords on, `simulate
// --tissue` reproduces the fit's closure from it, and a bad tissue file exits 2.
TEST(TissuePrefitCli, FitWritesTheTissueAndSimulateReproducesTheClosure) {
  const TissueProblem& p = tissueProblem();
  testing::TempDir dir;
  ValveCase with_seed = p.valve_case;
  with_seed.cords = p.base;
  writeCase(dir / "case", with_seed);
  const std::string case_dir = testing::quoted(dir / "case");
  const auto fit = testing::runChordfit("fit " + case_dir +
                                        " --no-prefit --tissue-prefit --max-sims 90 --threads 2 "
                                        "--quiet --out " +
                                        testing::quoted(dir / "fit"));
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const auto metrics = nlohmann::json::parse(testing::readText(dir / "fit" / "metrics.json"));
  EXPECT_TRUE(metrics["tissue_prefit_ran"].get<bool>());
  ASSERT_FALSE(metrics["tissue_prefit"].empty());
  EXPECT_EQ(metrics["tissue_prefit"][0], "P2 0.1");
  ASSERT_TRUE(std::filesystem::exists(dir / "fit" / "tissue.json"));
  const auto tissue = nlohmann::json::parse(testing::readText(dir / "fit" / "tissue.json"));
  EXPECT_EQ(tissue["stiffness"].size(), static_cast<std::size_t>(p.valve_case.mesh.V.rows()));
  EXPECT_NE(testing::readText(dir / "fit" / "report.md").find("tissue pre-fit"), std::string::npos);

  const auto simulated = testing::runChordfit(
      "simulate " + case_dir + " --cords " + testing::quoted(dir / "fit" / "cords.json") +
      " --tissue " + testing::quoted(dir / "fit" / "tissue.json") + " --quiet --out " +
      testing::quoted(dir / "sim"));
  ASSERT_EQ(simulated.exit_code, 0) << simulated.err;
  const auto again = nlohmann::json::parse(testing::readText(dir / "sim" / "metrics.json"));
  EXPECT_EQ(again["mean_mm"].get<double>(), metrics["mean_mm"].get<double>());

  // compare: the fit's cords on the fit's tissue reproduce the fit; the seed on the case's own.
  const auto compared = testing::runChordfit(
      "compare " + case_dir + " " + testing::quoted(dir / "case" / "cords.json") + " " +
      testing::quoted(dir / "fit" / "cords.json") + " --labels seed,fit --tissues -," +
      (dir / "fit" / "tissue.json").string() + " --quiet --out " + testing::quoted(dir / "cmp"));
  ASSERT_EQ(compared.exit_code, 0) << compared.err;
  const std::string csv = testing::readText(dir / "cmp" / "compare.csv");
  char fit_mean[32];
  std::snprintf(fit_mean, sizeof fit_mean, "%.6f", metrics["mean_mm"].get<double>());
  EXPECT_NE(csv.find(std::string(",") + fit_mean), std::string::npos) << csv << fit_mean;
  const auto miscounted =
      testing::runChordfit("compare " + case_dir + " " +
                           testing::quoted(dir / "fit" / "cords.json") + " --tissues -,- --quiet");
  EXPECT_EQ(miscounted.exit_code, 2);
  EXPECT_NE(miscounted.err.find("--tissues: 2 file(s) for 1 cord file(s)"), std::string::npos)
      << miscounted.err;

  // A budget too small for the tissue pre-fit: it does not run, and the report does not say it
  // kept the uniform tissue as if it had.
  const auto short_budget = testing::runChordfit("fit " + case_dir +
                                                 " --no-prefit --tissue-prefit --max-sims 5 "
                                                 "--no-uncertainty --quiet --out " +
                                                 testing::quoted(dir / "short"));
  ASSERT_EQ(short_budget.exit_code, 0) << short_budget.err;
  EXPECT_FALSE(
      nlohmann::json::parse(testing::readText(dir / "short" / "metrics.json"))["tissue_prefit_ran"]
          .get<bool>());
  EXPECT_NE(testing::readText(dir / "short" / "report.md")
                .find("- tissue pre-fit (stiffness factor per segment): not run: --max-sims 5 "
                      "leaves too few closures"),
            std::string::npos);

  testing::writeText(dir / "bad.json", R"({"stiffness": [1, 0.5, 1]})");
  const auto bad = testing::runChordfit("simulate " + case_dir + " --tissue " +
                                        testing::quoted(dir / "bad.json") + " --quiet --out " +
                                        testing::quoted(dir / "sim2"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("stiffness: 3 stiffness factors for a mesh of"), std::string::npos)
      << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "sim2" / "metrics.json"));
}

// The tissue retry (FitOptions::tissue_retry, on in `chordfit fit`): on the benchmark's
// prolapse-P3 seed 3 the cords alone leave the P3 flap down (its truth prolapses through soft
// lesion tissue), so the fit runs again from the pre-fits with the tissue pre-fit, makes the
// flap, fits the tracings better and keeps that; --no-tissue-retry gives the first fit alone.
TEST(TissueRetryCli, FitsAgainOnSofterTissueWhenTheFitMissesTheTracingsProlapse) {
  testing::TempDir dir;
  const std::string case_dir = testing::quoted(dir / "case");
  const auto made = testing::runChordfit(
      "make-case --preset prolapse-P3 --seed 3 --edge 2.5 --out " + case_dir + " --quiet");
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const std::string fit = "fit " + case_dir + " --max-sims 300 --fd-warm --no-uncertainty --out ";
  const auto first =
      testing::runChordfit(fit + testing::quoted(dir / "first") + " --no-tissue-retry");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const auto without = nlohmann::json::parse(testing::readText(dir / "first" / "metrics.json"));
  ASSERT_EQ(without["tracing_prolapse_segments"], nlohmann::json::array({"P3"}));
  ASSERT_FALSE(without["prolapse_reconstructed"].get<bool>())
      << "the cords alone make the P3 flap: the case no longer tests the retry";
  EXPECT_EQ(without["tissue_retry"]["ran"], false);
  EXPECT_EQ(without["tissue_retry"]["missing_segments"], nlohmann::json::array({"P3"}));
  EXPECT_NE(first.err.find("leave out --no-tissue-retry"), std::string::npos) << first.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "first" / "tissue.json"));

  // A budget the first optimisation spends: the retry is skipped, and both say so.
  const auto small =
      testing::runChordfit("fit " + case_dir + " --max-sims 50 --fd-warm --no-uncertainty --out " +
                           testing::quoted(dir / "small"));
  ASSERT_EQ(small.exit_code, 0) << small.err;
  const auto skipped = nlohmann::json::parse(testing::readText(dir / "small" / "metrics.json"));
  EXPECT_EQ(skipped["tissue_retry"]["ran"], false);
  EXPECT_EQ(skipped["tissue_retry"]["skipped"].get<std::string>().rfind("--max-sims 50 leaves ", 0),
            0u)
      << skipped["tissue_retry"].dump();
  EXPECT_NE(small.out.find("tissue retry: the tracings show prolapse in P3, the fit did not (data "
                           "cost "),
            std::string::npos)
      << small.out;
  EXPECT_EQ(small.out.find("data cost 0.000"), std::string::npos) << small.out;
  EXPECT_NE(small.err.find("softer tissue was not tried: the tissue retry did not run (--max-sims "
                           "50 leaves "),
            std::string::npos)
      << small.err;

  const auto second = testing::runChordfit(fit + testing::quoted(dir / "retry"));
  ASSERT_EQ(second.exit_code, 0) << second.err;
  const auto with = nlohmann::json::parse(testing::readText(dir / "retry" / "metrics.json"));
  const auto& retry = with["tissue_retry"];
  EXPECT_EQ(retry["missing_segments"], nlohmann::json::array({"P3"}));
  ASSERT_EQ(retry["ran"], true) << retry.dump();
  ASSERT_EQ(retry["kept"], true) << retry.dump();
  EXPECT_TRUE(with["prolapse_reconstructed"].get<bool>());
  EXPECT_EQ(retry["missing_segments_after"], nlohmann::json::array());
  EXPECT_LT(retry["data_cost_with"].get<double>(), 0.9 * retry["data_cost_without"].get<double>());
  EXPECT_LT(with["mean_mm"].get<double>(), without["mean_mm"].get<double>());
  // The first optimisation is the fit without the retry, closure for closure.
  EXPECT_EQ(retry["mean_mm_without"].get<double>(), without["mean_mm"].get<double>());
  EXPECT_EQ(with["forward_sims"].get<int>(),
            without["forward_sims"].get<int>() + retry["forward_sims"].get<int>());
  EXPECT_LE(with["forward_sims"].get<int>(), 301);
  EXPECT_EQ(with["tissue_prefit"], retry["tissue"]);
  ASSERT_FALSE(retry["tissue"].empty());
  EXPECT_EQ(retry["tissue"][0].get<std::string>().rfind("P3 ", 0), 0u) << retry.dump();
  // The fit makes the flap: no advice.
  EXPECT_EQ(second.err.find("note: the tracings show prolapse"), std::string::npos) << second.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "retry" / "tissue.json"));
  EXPECT_NE(second.out.find("tissue retry: the tracings show prolapse in P3, the fit does not"),
            std::string::npos)
      << second.out;
  EXPECT_NE(
      testing::readText(dir / "retry" / "report.md").find("- tissue retry: the tracings show"),
      std::string::npos);
  EXPECT_NE(testing::readText(dir / "retry" / "convergence.csv").find("retry ceres"),
            std::string::npos);

  // The fit says how to reproduce its closure; simulate and compare, given the fit's cords
  // without its tissue, say that tissue.json lies beside them.
  EXPECT_NE(second.out.find("the fitted closure is on softer tissue (tissue retry): chordfit "
                            "simulate "),
            std::string::npos)
      << second.out;
  const std::string cords = testing::quoted(dir / "retry" / "cords.json");
  const std::string beside = "tissue.json lies beside ";
  const auto own = testing::runChordfit("simulate " + case_dir + " --cords " + cords +
                                        " --quiet --out " + testing::quoted(dir / "own"));
  ASSERT_EQ(own.exit_code, 0) << own.err;
  EXPECT_NE(own.err.find("note: simulate: "), std::string::npos) << own.err;
  EXPECT_NE(own.err.find(beside), std::string::npos) << own.err;
  const auto softer =
      testing::runChordfit("simulate " + case_dir + " --cords " + cords + " --tissue " +
                           testing::quoted(dir / "retry" / "tissue.json") + " --quiet --out " +
                           testing::quoted(dir / "softer"));
  ASSERT_EQ(softer.exit_code, 0) << softer.err;
  EXPECT_EQ(softer.err.find(beside), std::string::npos) << softer.err;
  EXPECT_EQ(nlohmann::json::parse(testing::readText(dir / "softer" / "metrics.json"))["mean_mm"],
            with["mean_mm"]);
  const auto compared = testing::runChordfit("compare " + case_dir + " " + cords + " --quiet");
  ASSERT_EQ(compared.exit_code, 0) << compared.err;
  EXPECT_NE(compared.err.find("note: compare: "), std::string::npos) << compared.err;

  // sweep-cord takes the fit's tissue too: its scale-1 closure is the fit's.
  const std::string sweep = "sweep-cord " + case_dir + " --cords " + cords +
                            " --range 0.004 --step 0.001 --window 2 --out ";
  const auto swept = testing::runChordfit(sweep + testing::quoted(dir / "sweep") + " --tissue " +
                                          testing::quoted(dir / "retry" / "tissue.json"));
  ASSERT_EQ(swept.exit_code, 0) << swept.err;
  EXPECT_EQ(swept.err.find(beside), std::string::npos) << swept.err;
  const std::string csv = testing::readText(dir / "sweep" / "sweep.csv");
  const std::size_t row = csv.find("\n1,");
  ASSERT_NE(row, std::string::npos) << csv;
  EXPECT_NEAR(std::stod(csv.substr(row + 3)), with["mean_mm"].get<double>(), 1e-9) << csv;
  const auto swept_own = testing::runChordfit(sweep + testing::quoted(dir / "sweep_own"));
  ASSERT_EQ(swept_own.exit_code, 0) << swept_own.err;
  EXPECT_NE(swept_own.err.find("note: sweep-cord: "), std::string::npos) << swept_own.err;

  // The retry is as deterministic as the rest of the fit: one thread gives the same files.
  const auto one =
      testing::runChordfit(fit + testing::quoted(dir / "one") + " --threads 1 --quiet");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  for (const char* file : {"cords.json", "tissue.json", "closed.ply"}) {
    EXPECT_EQ(testing::readText(dir / "one" / file), testing::readText(dir / "retry" / file))
        << file;
  }
}

}  // namespace
}  // namespace chordfit
