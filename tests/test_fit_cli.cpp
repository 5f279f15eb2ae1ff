// `chordfit fit` end to end: bad input exits 2 with a message naming the option or file; a
// tiny fit writes every output with the documented keys; locked cords stay bit for bit.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "core/csv_text.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

using testing::runChordfit;
using testing::TempDir;

using testing::quoted;

std::filesystem::path smallCase() {
  return std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
}

// `fit SMALL_CASE ARGUMENTS --out OUT`, expected to succeed: its metrics.json (an empty object,
// with a failure recorded, when it did not).
nlohmann::json fitSmallCase(const std::string& arguments, const std::filesystem::path& out) {
  const auto r =
      runChordfit("fit " + quoted(smallCase()) + " " + arguments + " --out " + quoted(out));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  if (r.exit_code != 0) return nlohmann::json::object();
  return nlohmann::json::parse(testing::readText(out / "metrics.json"));
}

// `fit SMALL_CASE ARGUMENTS --out DIR/fit`, expected to be refused before any work: exit 2 and
// no fit output. Returns stderr for the test's own checks of the message.
std::string refusedFitMessage(const std::string& arguments) {
  TempDir dir;
  const auto r =
      runChordfit("fit " + quoted(smallCase()) + " " + arguments + " --out " + quoted(dir / "fit"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  // Refused before any work: not even the --out directory (nor a staging directory in it).
  EXPECT_FALSE(std::filesystem::exists(dir / "fit")) << arguments;
  return r.err;
}

// Every entry under `dir` (its path relative to `dir`) with its bytes ("" for a directory):
// a snapshot to tell whether a run changed anything there.
std::map<std::string, std::string> directorySnapshot(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    const std::string name = entry.path().lexically_relative(dir).generic_string();
    files[name] = entry.is_regular_file() ? testing::readText(entry.path()) : std::string();
  }
  return files;
}

// The names in `snapshot` of staging directories or what is in them (".staging-<pid>").
std::vector<std::string> stagingEntries(const std::map<std::string, std::string>& snapshot) {
  std::vector<std::string> staging;
  for (const auto& [name, bytes] : snapshot)
    if (name.rfind(".staging", 0) == 0 || name.find("/.staging") != std::string::npos)
      staging.push_back(name);
  return staging;
}

// "at most 3 forward runs, 1 threads": the fit's first line counts one thread in the singular.
TEST(FitCommand, CountsOneThreadInTheSingular) {
  TempDir dir;
  const auto r = runChordfit("fit " + quoted(smallCase()) +
                             " --no-prefit --no-uncertainty --max-sims 3 --threads 1 --out " +
                             quoted(dir / "fit"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(": 32 cords, scales, ceres, at most 3 forward runs, 1 thread\n"),
            std::string::npos)
      << r.out;
}

TEST(FitCommand, RejectsAnUnknownOptimizerWithExitCode2) {
  const std::string err = refusedFitMessage("--optimizer newton");
  EXPECT_NE(err.find("--optimizer"), std::string::npos) << err;
  EXPECT_NE(err.find("newton"), std::string::npos) << err;
}

TEST(FitCommand, ADirectoryInTheWayOfAnOutputFileExitsWith2BeforeFitting) {
  TempDir dir;
  std::filesystem::create_directories(dir / "fit" / "report.md");
  const auto r = runChordfit("fit " + quoted(smallCase()) + " --out " + quoted(dir / "fit"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: fit: --out: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("report.md: a directory of that name is in the way"), std::string::npos)
      << r.err;
  EXPECT_EQ(r.out.find("fitting"), std::string::npos) << "fitted first: " << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "fit" / "cords.json"));
}

// The fitted cords.json would replace the seed the user put in --out, or, with --out the case
// directory, the case's own cords: refused before the fit, both files left as they were.
TEST(FitCommand, RefusesAnOutputThatWouldReplaceOneOfItsInputs) {
  TempDir dir;
  std::filesystem::copy(smallCase(), dir / "case", std::filesystem::copy_options::recursive);
  std::filesystem::create_directories(dir / "fit");
  std::filesystem::copy_file(dir / "case" / "cords.json", dir / "fit" / "cords.json");
  const std::string seed = testing::readText(dir / "fit" / "cords.json");
  const auto r = runChordfit("fit " + quoted(dir / "case") + " --seed-cords " +
                             quoted(dir / "fit" / "cords.json") + " --out " + quoted(dir / "fit"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("cords.json: is an input of this run; fit would write over it"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(testing::readText(dir / "fit" / "cords.json"), seed);
  const auto into_case =
      runChordfit("fit " + quoted(dir / "case") + " --out " + quoted(dir / "case"));
  EXPECT_EQ(into_case.exit_code, 2) << into_case.err;
  EXPECT_NE(into_case.err.find("is an input of this run"), std::string::npos) << into_case.err;
  EXPECT_EQ(testing::readText(dir / "case" / "cords.json"), seed);
  EXPECT_FALSE(std::filesystem::exists(dir / "case" / "report.md"));
}

TEST(FitCommand, RejectsAnUnknownParameterModeWithExitCode2) {
  const std::string err = refusedFitMessage("--params lengths");
  EXPECT_NE(err.find("error: fit: --params: expected scales, groups or scales+tips, got "
                     "\"lengths\""),
            std::string::npos)
      << err;
}

TEST(FitCommand, RejectsAMissingSeedFileWithExitCode2) {
  TempDir dir;
  const std::string err = refusedFitMessage("--seed-cords " + quoted(dir / "nowhere.json"));
  EXPECT_NE(err.find("nowhere.json"), std::string::npos) << err;
}

// A seed cord set with a field of the wrong type: exit 2 naming the file and the field, before
// any work (no --out directory).
TEST(FitCommand, RejectsASeedWithABadFieldNamingTheFileAndTheField) {
  TempDir dir;
  auto cords = nlohmann::json::parse(testing::readText(smallCase() / "cords.json"));
  ASSERT_GT(cords["cords"].size(), 3u);
  cords["cords"][3]["rest_length_mm"] = "x";
  testing::writeText(dir / "bad.json", cords.dump(2));
  const std::string err = refusedFitMessage("--seed-cords " + quoted(dir / "bad.json"));
  EXPECT_NE(err.find("bad.json: cords[3].rest_length_mm: expected a number"), std::string::npos)
      << err;
}

// A cord set without cords gave a "fit" of nothing with exit 0 and every output written.
TEST(FitCommand, RefusesASeedWithoutCords) {
  TempDir dir;
  auto cords = nlohmann::json::parse(testing::readText(smallCase() / "cords.json"));
  cords["cords"] = nlohmann::json::array();
  testing::writeText(dir / "empty.json", cords.dump());
  const std::string message = refusedFitMessage("--seed-cords " + quoted(dir / "empty.json"));
  EXPECT_NE(message.find("empty.json has no cords: nothing to fit"), std::string::npos) << message;
}

TEST(FitCommand, RejectsInvertedScaleBoundsWithExitCode2) {
  const std::string err = refusedFitMessage("--scale-bounds 1.5,0.7");
  EXPECT_NE(err.find("error: fit: --scale-bounds: need two numbers 0 < LO < HI"), std::string::npos)
      << err;
  EXPECT_NE(err.find("got 1.5,0.7"), std::string::npos) << err;
}

// An upper bound that lets a cord outgrow what a cord set may hold (1000 mm) used to fail only
// after the fit, when its cords.json was read back for the fitted closure.
TEST(FitCommand, RejectsAnUpperScaleBoundNoCordSetCanHoldBeforeFitting) {
  TempDir dir;
  const auto r = runChordfit("fit " + quoted(smallCase()) + " --scale-bounds 0.7,100 --out " +
                             quoted(dir / "fit"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: fit: --scale-bounds: the upper bound 100 lets cord 0 of the "
                       "case's cord set ("),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("a cord set holds at most 1000 mm"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "fit"));
}

// A long seed cord (700 mm, within what a cord set holds) beyond the reach of the default
// bounds: the message named neither the seed file nor the cord.
TEST(FitCommand, AnUpperScaleBoundALongSeedCordOutgrowsNamesTheFileAndTheCord) {
  TempDir dir;
  auto cords = nlohmann::json::parse(testing::readText(smallCase() / "cords.json"));
  ASSERT_GT(cords["cords"].size(), 3u);
  cords["cords"][3]["rest_length_mm"] = 700;
  cords["cords"][3]["seed_rest_length_mm"] = 700;
  testing::writeText(dir / "long.json", cords.dump(2));
  const std::string err = refusedFitMessage("--seed-cords " + quoted(dir / "long.json"));
  EXPECT_NE(err.find("error: fit: --scale-bounds: the upper bound 1.5 lets cord 3 of " +
                     (dir / "long.json").string() + " (700 mm) reach 1050 mm"),
            std::string::npos)
      << err;
}

// The same for a lower bound that lets a cord shrink below the 1 mm a cord set must hold.
TEST(FitCommand, RejectsALowerScaleBoundNoCordSetCanHoldBeforeFitting) {
  TempDir dir;
  const auto r = runChordfit("fit " + quoted(smallCase()) + " --scale-bounds 0.02,1.5 --out " +
                             quoted(dir / "fit"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: fit: --scale-bounds: the lower bound 0.02 lets cord 0 of the "
                       "case's cord set ("),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("a cord set holds at least 1 mm"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "fit"));
}

TEST(FitCommand, RejectsAnUnknownDistanceWithExitCode2) {
  const std::string err = refusedFitMessage("--distance nearest");
  EXPECT_NE(err.find("--distance"), std::string::npos) << err;
  EXPECT_NE(err.find("nearest"), std::string::npos) << err;
}

TEST(FitCommand, RejectsANegativeSectionWeightWithExitCode2) {
  const std::string err = refusedFitMessage("--section-weight -0.1");
  EXPECT_NE(err.find("error: fit: --section-weight: must be in [0, 1000], got -0.1"),
            std::string::npos)
      << err;
}

TEST(FitCommand, RejectsANegativeTipWeightWithExitCode2) {
  const std::string err = refusedFitMessage("--params scales+tips --tip-weight -1");
  EXPECT_NE(err.find("error: fit: --tip-weight: must be in [0, 1000], got -1"), std::string::npos)
      << err;
}

// Values each option's positivity let through that made a fit meaningless with exit 0: a
// weight of 1e308 overflowed the cost (the fit returned its seed), a step of 1e-300 gave
// Jacobian columns of 0, a tip step of 1e308 mm diverged every difference closure.
TEST(FitCommand, RefusesWeightsAndStepsThatMakeTheCostOrTheJacobianMeaningless) {
  const std::pair<std::string, std::string> cases[] = {
      {"--section-weight 1e308", "error: fit: --section-weight: must be in [0, 1000], got 1e+308"},
      {"--params scales+tips --tip-weight 1001",
       "error: fit: --tip-weight: must be in [0, 1000], got 1001"},
      {"--fd-step 1e-300",
       "error: fit: --fd-step: 1e-300 is below 1e-06, where a central "
       "difference measures the closure's stopping tolerance"},
      {"--params scales+tips --fd-tip-step 1e308",
       "error: fit: --fd-tip-step: must be in [0.0001, 5] mm, got 1e+308"},
      {"--params scales+tips --fd-tip-step 1e-5",
       "error: fit: --fd-tip-step: must be in [0.0001, 5] mm, got 1e-05"}};
  for (const auto& [options, message] : cases) {
    const std::string err = refusedFitMessage(options);
    EXPECT_NE(err.find(message), std::string::npos) << options << ": " << err;
  }
}

// The tip prior (--tip-weight) is recorded where a reader of the results looks for it.
TEST(FitCommand, TipWeightIsRecordedInMetricsAndReport) {
  TempDir dir;
  const auto metrics = fitSmallCase(
      "--params scales+tips --tip-weight 0.5 --no-prefit --no-uncertainty --max-sims 1",
      dir / "fit");
  ASSERT_FALSE(metrics.empty());
  EXPECT_EQ(metrics["tip_weight"].get<double>(), 0.5);
  const std::string report = testing::readText(dir / "fit" / "report.md");
  EXPECT_NE(report.find("PM tip offsets: box ±8 mm per axis, prior 0.5 mm of residual per mm"),
            std::string::npos);
  // The tips' offsets have their own table (SD "–" without the uncertainty), and the run's
  // options are in metrics.json.
  EXPECT_NE(report.find("| tip anterolateral x | 0.000 | – |"), std::string::npos) << report;
  EXPECT_EQ(metrics["options"]["prefit"], false);
  EXPECT_EQ(metrics["options"]["uncertainty"], false);
  EXPECT_EQ(metrics["options"]["tip_box_mm"].get<double>(), 8.0);

  // With the uncertainty, each offset says whether the tracings determine it (more than 2 SD
  // from 0); the start's zero offsets are not, and the terminal says how many are.
  const auto r =
      runChordfit("fit " + quoted(smallCase()) +
                  " --params scales+tips --no-prefit --max-sims 1 --out " + quoted(dir / "sd"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("PM tips: 0 of 6 tip offsets determined (more than 2 SD from 0)"),
            std::string::npos)
      << r.out;
  const std::string with_sd = testing::readText(dir / "sd" / "report.md");
  EXPECT_NE(with_sd.find("| Parameter | Offset (mm) | ± SD (mm) | Determined |"),
            std::string::npos);
  EXPECT_TRUE(std::regex_search(with_sd, std::regex("\\| tip anterolateral x \\| 0\\.000 \\| "
                                                    "[0-9.]+ \\| no \\|")))
      << with_sd;
}

// A seed whose free cords are all manual (edit-cords --all): the cord pre-fits would close
// the seed again for every factor, so they do not run, and the fit says why.
TEST(FitCommand, SkipsThePrefitsWhenEveryFreeCordIsManual) {
  TempDir dir;
  ASSERT_EQ(runChordfit("edit-cords " + quoted(smallCase()) + " --all 0.8 --out " +
                        quoted(dir / "seed.json"))
                .exit_code,
            0);
  const auto r =
      runChordfit("fit " + quoted(smallCase()) + " --seed-cords " + quoted(dir / "seed.json") +
                  " --no-uncertainty --max-sims 20 --out " + quoted(dir / "fit"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("pre-fits skipped: every free cord is manual"), std::string::npos) << r.out;
  const std::string csv = testing::readText(dir / "fit" / "convergence.csv");
  EXPECT_EQ(csv.find("\nprefit,"), std::string::npos) << csv;
  EXPECT_EQ(csv.find("\nsegments,"), std::string::npos) << csv;
  // The budget goes to the optimiser alone (here too small for its first Jacobian of the 32
  // cords: the seed's closure, then the one written out).
  const auto metrics = nlohmann::json::parse(testing::readText(dir / "fit" / "metrics.json"));
  EXPECT_EQ(metrics["forward_sims"].get<int>(), 2);
  EXPECT_FALSE(metrics["prefit_ran"].get<bool>());
  EXPECT_FALSE(metrics["segment_prefit_ran"].get<bool>());
  EXPECT_NE(metrics["prefit_skipped"].get<std::string>().find("every free cord is manual"),
            std::string::npos);
  EXPECT_NE(testing::readText(dir / "fit" / "report.md")
                .find("- global pre-fit: skipped: every free cord is manual"),
            std::string::npos);
}

TEST(FitCommand, NamesTheNonPositiveCountOrStepWithExitCode2) {
  for (const std::string option :
       {"--max-sims 0", "--tip-box -1", "--fd-step 0", "--fd-tip-step -0.5"}) {
    const std::string err = refusedFitMessage(option);
    const std::string name = option.substr(0, option.find(' '));
    EXPECT_NE(err.find("error: fit: " + name + ": must be a positive number"), std::string::npos)
        << err;
  }
  // --threads is checked with every command's (tools/main.cpp), in its own words.
  const std::string err = refusedFitMessage("--threads 0");
  EXPECT_NE(err.find("error: fit: --threads: "), std::string::npos) << err;
  EXPECT_NE(err.find("got 0"), std::string::npos) << err;
}

// A tip box whose corner lies beyond the case's reach (50 mm for the small case: a box of at
// most 50 / sqrt(3) = 28.87 mm) would let a tip go where no case file may put one: 1e308 gave
// crs2 an infinite domain. Checked only where it acts (with other --params it is noted).
TEST(FitCommand, RefusesATipBoxBeyondTheCasesReach) {
  for (const std::string box : {"28.9", "1e308"}) {
    const std::string err = refusedFitMessage("--params scales+tips --tip-box " + box);
    EXPECT_NE(err.find("error: fit: --tip-box: " + (box == "1e308" ? std::string("1e+308") : box) +
                       " mm reaches beyond this case: at most 28.8 mm"),
              std::string::npos)
        << err;
  }
  TempDir dir;
  for (const std::string params : {"scales+tips --tip-box 28.8", "scales --tip-box 100"}) {
    const auto r = runChordfit("fit " + quoted(smallCase()) + " --params " + params +
                               " --max-sims 1 --no-prefit --no-uncertainty --quiet --out " +
                               quoted(dir / "fit"));
    EXPECT_EQ(r.exit_code, 0) << params << "\n" << r.err;
  }
}

// The section residuals (--section-weight) reach the fit: recorded in metrics.json and
// report.md, and the data cost of the start changes (the seed's sections stray from the
// tracings), while AvgD, the tracing points' mean, does not.
TEST(FitCommand, SectionWeightIsRecordedAndAddsToTheCostNotToAvgD) {
  TempDir dir;
  nlohmann::json runs[2];
  for (int k = 0; k < 2; ++k) {
    const std::string out = k == 0 ? "plain" : "sections";
    const auto r = runChordfit(
        "fit " + quoted(smallCase()) + " --no-prefit --no-uncertainty --max-sims 1" +
        (k == 0 ? std::string() : " --section-weight 0.5") + " --out " + quoted(dir / out));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    runs[k] = nlohmann::json::parse(testing::readText(dir / out / "metrics.json"));
  }
  EXPECT_EQ(runs[0]["section_weight"].get<double>(), 0.0);
  EXPECT_EQ(runs[1]["section_weight"].get<double>(), 0.5);
  EXPECT_GT(runs[1]["initial_cost"].get<double>(), runs[0]["initial_cost"].get<double>());
  EXPECT_EQ(runs[1]["initial_mean_mm"].get<double>(), runs[0]["initial_mean_mm"].get<double>());
  EXPECT_NE(testing::readText(dir / "sections" / "report.md").find("section residuals: weight 0.5"),
            std::string::npos);
  EXPECT_FALSE(runs[1].contains("uncertainty")) << "--no-uncertainty";
  EXPECT_FALSE(std::filesystem::exists(dir / "sections" / "uncertainty.csv"));
}

// One free cord (the others locked, as the paper's editor would write them): 1 + 2 + 1 runs.
// A seed edited past the scale bounds (every cord x 0.6, manual and unlocked): the seed row,
// initial_mean_mm and the report are the seed as given, the closure `simulate` makes of it,
// not the seed clamped into the bounds that the optimiser starts from.
TEST(FitCommand, ReportsTheSeedAsGivenWhenItLiesOutsideTheBounds) {
  TempDir dir;
  ASSERT_EQ(runChordfit("edit-cords " + quoted(smallCase()) + " --all 0.6 --out " +
                        quoted(dir / "seed.json"))
                .exit_code,
            0);
  ASSERT_EQ(
      runChordfit("simulate " + quoted(smallCase()) + " --cords " + quoted(dir / "seed.json") +
                  " --quiet --threads 1 --out " + quoted(dir / "sim"))
          .exit_code,
      0);
  const auto r = runChordfit(
      "fit " + quoted(smallCase()) + " --seed-cords " + quoted(dir / "seed.json") +
      " --no-prefit --no-uncertainty --max-sims 3 --quiet --out " + quoted(dir / "fit"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto simulated = nlohmann::json::parse(testing::readText(dir / "sim" / "metrics.json"));
  const auto fitted = nlohmann::json::parse(testing::readText(dir / "fit" / "metrics.json"));
  EXPECT_DOUBLE_EQ(fitted["initial_mean_mm"].get<double>(), simulated["mean_mm"].get<double>());
}

// --set applies to every closure of the fit, the written one included: the seed row is the
// closure `simulate --set` makes; the override is in metrics.json and report.md. A bad --set
// is refused before the fit.
TEST(FitCommand, SetOverridesTheSimulatorSettingsOfEveryClosure) {
  TempDir dir;
  const std::string set = " --set youngs_modulus_mpa=4";
  ASSERT_EQ(
      runChordfit("simulate " + quoted(smallCase()) + set + " --quiet --out " + quoted(dir / "sim"))
          .exit_code,
      0);
  const auto r = runChordfit("fit " + quoted(smallCase()) + set +
                             " --no-prefit --no-uncertainty --max-sims 3 --quiet --out " +
                             quoted(dir / "fit"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto simulated = nlohmann::json::parse(testing::readText(dir / "sim" / "metrics.json"));
  const auto fitted = nlohmann::json::parse(testing::readText(dir / "fit" / "metrics.json"));
  EXPECT_DOUBLE_EQ(fitted["initial_mean_mm"].get<double>(), simulated["mean_mm"].get<double>());
  EXPECT_EQ(fitted["settings_overrides"], nlohmann::json({"youngs_modulus_mpa=4"}));
  EXPECT_NE(testing::readText(dir / "fit" / "report.md").find("(--set): `youngs_modulus_mpa=4`"),
            std::string::npos);
  const auto bad = runChordfit("fit " + quoted(smallCase()) + " --set thickness_mm=0 --out " +
                               quoted(dir / "bad"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("fit: --set: simulation.thickness_mm"), std::string::npos) << bad.err;
  EXPECT_EQ(bad.out.find("fitting"), std::string::npos) << "fitted first: " << bad.out;
}

// The same seed with a budget of one closure: the seed's own closure takes it, and nothing is
// left to close the clamped start; that is a usage error, not a failed simulation.
TEST(FitCommand, ABudgetTooSmallForTheClampedStartExitsWith2NamingMaxSims) {
  TempDir dir;
  ASSERT_EQ(runChordfit("edit-cords " + quoted(smallCase()) + " --all 0.6 --out " +
                        quoted(dir / "seed.json"))
                .exit_code,
            0);
  const auto r =
      runChordfit("fit " + quoted(smallCase()) + " --seed-cords " + quoted(dir / "seed.json") +
                  " --max-sims 1 --quiet --out " + quoted(dir / "fit"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--max-sims 1"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "fit" / "cords.json"));
}

// Bounds that exclude the seed and a budget that leaves Ceres no step: the fit writes the
// clamped start, worse than the seed, and said nothing about it.
TEST(FitCommand, AFitWorseThanTheSeedSaysWhyInTheTerminalAndTheReport) {
  TempDir dir;
  const auto r = runChordfit("fit " + quoted(smallCase()) +
                             " --scale-bounds 1.1,1.5 --max-sims 3 --no-uncertainty --out " +
                             quoted(dir / "fit"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto metrics = nlohmann::json::parse(testing::readText(dir / "fit" / "metrics.json"));
  ASSERT_GT(metrics["mean_mm"].get<double>(), metrics["initial_mean_mm"].get<double>());
  EXPECT_NE(r.err.find("note: the fit ends worse than the seed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("clamped into them"), std::string::npos) << r.err;
  EXPECT_NE(testing::readText(dir / "fit" / "report.md").find("**the fit ends worse than the seed"),
            std::string::npos);
  // A fit that improves on the seed says nothing of the kind.
  const auto better = runChordfit("fit " + quoted(smallCase()) +
                                  " --max-sims 15 --no-uncertainty --out " + quoted(dir / "ok"));
  ASSERT_EQ(better.exit_code, 0) << better.err;
  EXPECT_EQ(better.err.find("worse than the seed"), std::string::npos) << better.err;
}

// The small case's cords with every cord but cord 0 locked (manual), written to `file`.
nlohmann::json seedWithOnlyCordZeroFree(const std::filesystem::path& file) {
  auto seed = nlohmann::json::parse(testing::readText(smallCase() / "cords.json"));
  for (std::size_t c = 1; c < seed["cords"].size(); ++c) {
    seed["cords"][c]["locked"] = true;
    seed["cords"][c]["provenance"] = "manual";
  }
  testing::writeText(file, seed.dump(2));
  return seed;
}

// Each locked cord of `seed` (every cord but 0) written back exactly as it was: its whole
// object (rest length, scale, provenance, lock, attachment, group), in `fitted` cords.json.
void expectLockedCordsAsInTheSeed(const nlohmann::json& seed, const nlohmann::json& fitted,
                                  const std::string& what) {
  ASSERT_EQ(fitted["cords"].size(), seed["cords"].size()) << what;
  for (std::size_t c = 1; c < seed["cords"].size(); ++c)
    EXPECT_EQ(fitted["cords"][c].dump(), seed["cords"][c].dump()) << what << ": cord " << c;
}

TEST(FitCommand, WritesEveryOutputAndKeepsLockedCordsBitForBit) {
  TempDir dir;
  const auto seed = seedWithOnlyCordZeroFree(dir / "seed.json");
  const auto r =
      runChordfit("fit " + quoted(smallCase()) + " --seed-cords " + quoted(dir / "seed.json") +
                  " --no-prefit --max-sims 5 --threads 2 --out " + quoted(dir / "fit"));
  // 5 = the seed, a Jacobian (2), a trial step and the slack release's closure.
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ceres    iter"), std::string::npos) << r.out;
  {  // the progress lines' columns line up whatever the stage ("seed", "ceres", "release")
    std::istringstream lines(r.out);
    std::set<std::size_t> iter_columns;
    for (std::string line; std::getline(lines, line);)
      if (line.find(" iter ") != std::string::npos) iter_columns.insert(line.find(" iter "));
    EXPECT_EQ(iter_columns.size(), 1u) << r.out;
  }
  EXPECT_NE(r.out.find("| seed |"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find(".staging"), std::string::npos) << "no path of the staging directory";
  for (const char* file : {"cords.json", "closed.ply", "closed.vtk", "metrics.json",
                           "convergence.csv", "convergence.svg", "sections.svg", "report.md"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "fit" / file)) << file;
  }
  // The seed and the fitted closure against the tracings, one panel per plane (3 planes).
  const std::string sections = testing::readText(dir / "fit" / "sections.svg");
  for (const char* text : {">seed closure<", ">fitted closure, anterior<",
                           ">fitted closure, posterior<", ">tracing points<", ">plane 2: "}) {
    EXPECT_NE(sections.find(text), std::string::npos) << text;
  }
  // Each stage in convergence.svg's legend: the seed and the optimiser's iterations.
  const std::string convergence = testing::readText(dir / "fit" / "convergence.svg");
  for (const char* text : {">seed<", ">ceres iterations<"})
    EXPECT_NE(convergence.find(text), std::string::npos) << text;
  const auto metrics = nlohmann::json::parse(testing::readText(dir / "fit" / "metrics.json"));
  for (const char* key :
       {"mean_mm", "area_mm2", "prolapse_segments", "optimizer", "forward_sims", "fit_seconds",
        "initial_mean_mm", "unsettled_sims", "averaged_steps", "distance", "slack_release"}) {
    EXPECT_TRUE(metrics.contains(key)) << key;
  }
  for (const char* key : {"proposed_cords", "kept", "primary_reference", "secondary_reference"}) {
    EXPECT_TRUE(metrics["slack_release"].contains(key)) << key;
  }
  EXPECT_NE(testing::readText(dir / "fit" / "report.md").find("- slack release: "),
            std::string::npos);
  EXPECT_EQ(metrics["optimizer"], "ceres");
  EXPECT_EQ(metrics["distance"], "own-leaflet");     // the default data residual
  EXPECT_LE(metrics["forward_sims"].get<int>(), 6);  // budget 5 + the closure written
  EXPECT_LE(metrics["unsettled_sims"].get<int>(), metrics["forward_sims"].get<int>());
  EXPECT_LT(metrics["unsettled_sims"].get<int>(), metrics["forward_sims"].get<int>());
  EXPECT_LE(metrics["mean_mm"].get<double>(), metrics["initial_mean_mm"].get<double>());
  const auto fitted = nlohmann::json::parse(testing::readText(dir / "fit" / "cords.json"));
  ASSERT_EQ(fitted["cords"].size(), seed["cords"].size());
  for (std::size_t c = 1; c < seed["cords"].size(); ++c) {
    EXPECT_EQ(fitted["cords"][c]["rest_length_mm"].get<double>(),
              seed["cords"][c]["rest_length_mm"].get<double>())
        << c;
    EXPECT_EQ(fitted["cords"][c]["provenance"], "manual") << c;
  }
  expectLockedCordsAsInTheSeed(seed, fitted, "--params scales");
  // The free cord moved (a fit that did nothing would pass the checks above), and the tips,
  // not fitted with --params scales, are the seed's.
  EXPECT_NE(fitted["cords"][0]["rest_length_mm"].get<double>(),
            seed["cords"][0]["rest_length_mm"].get<double>());
  EXPECT_EQ(fitted["cords"][0]["provenance"], "fitted");
  EXPECT_EQ(fitted["tips"].dump(), seed["tips"].dump());
  // The free cord's uncertainty: one parameter row, its SD and sensitivity in the report.
  const auto& u = metrics["uncertainty"];
  EXPECT_EQ(u["free_cords"].get<int>(), 1);
  EXPECT_LE(u["identified_cords"].get<int>(), u["free_cords"].get<int>());
  EXPECT_GT(u["residual_sd_mm"].get<double>(), 0.0);
  const std::string csv = testing::readText(dir / "fit" / "uncertainty.csv");
  EXPECT_EQ(csv.rfind("parameter,name,kind,value,sd,", 0), 0u) << csv;
  EXPECT_NE(csv.find("\n0,\"cord 0\",scale,"), std::string::npos) << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 2) << "header + one parameter";
  const std::string report = testing::readText(dir / "fit" / "report.md");
  EXPECT_NE(report.find("± SD (%)"), std::string::npos);
  EXPECT_NE(report.find("Closed span (mm)"), std::string::npos);
  EXPECT_NE(report.find(std::to_string(metrics["slack_cords"].get<int>()) + " of " +
                        std::to_string(seed["cords"].size()) + " cords are slack"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("of 1 free cords are determined"), std::string::npos);
  EXPECT_NE(report.find("| seed |"), std::string::npos);
  EXPECT_NE(report.find("| fit |"), std::string::npos);
  EXPECT_NE(report.find("Fitted length"), std::string::npos);
}

// The same seed with --params groups (cord 0 alone in the only free group factor) and with
// --params scales+tips (the tips move, within the tip box): the locked cords are written back
// exactly as they were either way.
TEST(FitCommand, KeepsLockedCordsBitForBitWithGroupsAndWithTips) {
  TempDir dir;
  const auto seed = seedWithOnlyCordZeroFree(dir / "seed.json");
  const std::string fit = "--seed-cords " + quoted(dir / "seed.json") +
                          " --no-prefit --no-uncertainty --threads 2 --quiet ";
  // 5 = the seed, a Jacobian of the one factor (2), a trial step and the release's closure.
  ASSERT_FALSE(fitSmallCase(fit + "--params groups --max-sims 5", dir / "groups").empty());
  const auto groups = nlohmann::json::parse(testing::readText(dir / "groups" / "cords.json"));
  expectLockedCordsAsInTheSeed(seed, groups, "--params groups");
  EXPECT_NE(groups["cords"][0]["rest_length_mm"].get<double>(),
            seed["cords"][0]["rest_length_mm"].get<double>());
  EXPECT_EQ(groups["cords"][0]["provenance"], "fitted");
  EXPECT_EQ(groups["tips"].dump(), seed["tips"].dump());

  // 20 = the seed, a Jacobian of 7 parameters (14: a scale and two tips' 3 offsets), a trial
  // step and the release's closure, and a few to spare.
  const auto metrics = fitSmallCase(fit + "--params scales+tips --max-sims 20", dir / "tips");
  ASSERT_FALSE(metrics.empty());
  const double box = metrics["options"]["tip_box_mm"].get<double>();
  const auto tips = nlohmann::json::parse(testing::readText(dir / "tips" / "cords.json"));
  expectLockedCordsAsInTheSeed(seed, tips, "--params scales+tips");
  ASSERT_EQ(tips["tips"].size(), seed["tips"].size());
  double largest_move = 0.0;
  for (std::size_t t = 0; t < seed["tips"].size(); ++t) {
    EXPECT_EQ(tips["tips"][t]["name"], seed["tips"][t]["name"]);
    for (int axis = 0; axis < 3; ++axis) {
      const double move = tips["tips"][t]["position"][axis].get<double>() -
                          seed["tips"][t]["position"][axis].get<double>();
      EXPECT_LE(std::abs(move), box + 1e-9) << "tip " << t << " axis " << axis;
      largest_move = std::max(largest_move, std::abs(move));
    }
  }
  EXPECT_GT(largest_move, 0.1) << "the tips were fitted";
}

// Every cord locked, 20 % short: nothing to fit, so the locked-cord probe (report.md, metrics.json,
// the terminal) is how the user learns which locks hold the tracings off; --no-uncertainty
// skips it with the other after-fit diagnostics.
TEST(FitCommand, ProbesTheLockedCordsUnlessToldNotTo) {
  TempDir dir;
  ASSERT_EQ(runChordfit("edit-cords " + quoted(smallCase()) + " --all 0.8 --lock all --out " +
                        quoted(dir / "seed.json"))
                .exit_code,
            0);
  const std::string fit =
      "fit " + quoted(smallCase()) + " --seed-cords " + quoted(dir / "seed.json") + " --max-sims 3";
  const auto r = runChordfit(fit + " --out " + quoted(dir / "fit"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.find("note: locked cords hold the fit back: ") != std::string::npos ||
              r.out.find("locked cords: 32, ") != std::string::npos)
      << r.out << r.err;
  const auto metrics = nlohmann::json::parse(testing::readText(dir / "fit" / "metrics.json"));
  ASSERT_TRUE(metrics.contains("locked_cord_probe"));
  const auto& probe = metrics["locked_cord_probe"];
  ASSERT_EQ(probe["cords"].size(), 32u);
  int taut = 0;
  for (const auto& cord : probe["cords"]) {
    if (cord["slack"].get<bool>()) {
      EXPECT_FALSE(cord.contains("trial")) << cord;
      continue;
    }
    ++taut;
    ASSERT_TRUE(cord["trial"].contains("data_cost")) << cord;
    EXPECT_EQ(cord["trial"]["cords"], nlohmann::json::array({cord["cord"]}));
  }
  EXPECT_GT(taut, 0);
  EXPECT_EQ(probe["forward_sims"].get<int>(),
            3 * taut + static_cast<int>(probe["segments"].size()));
  EXPECT_EQ(metrics["forward_sims"].get<int>(), 2) << "the probe is outside --max-sims";
  const std::string report = testing::readText(dir / "fit" / "report.md");
  EXPECT_NE(report.find("## Locked cords"), std::string::npos);
  EXPECT_NE(report.find("| Cord | Group | Segment | Kind | Locked length (mm) |"),
            std::string::npos);
  // The cord table: the seed rest length, the start (the manual 0.8), the fitted length and the
  // scale of the seed rest length (the start was shown as "seed length" beside scale 0.8).
  const std::regex row(
      "\\n\\| 0 \\| [^|]+ \\| [a-z]+ \\| ([0-9.]+) \\| ([0-9.]+) \\| ([0-9.]+) \\| "
      "0\\.8000 \\|");
  std::smatch cells;
  ASSERT_TRUE(std::regex_search(report, cells, row)) << report;
  EXPECT_NEAR(std::stod(cells[2]), 0.8 * std::stod(cells[1]), 1e-3);
  EXPECT_EQ(cells[2], cells[3]) << "a locked cord keeps its start";

  // Closures cut short by the step cap: the probe's are counted apart from the fit's.
  const auto capped = runChordfit(fit + " --set max_steps=150 --out " + quoted(dir / "capped"));
  ASSERT_EQ(capped.exit_code, 0) << capped.err;
  const auto capped_metrics =
      nlohmann::json::parse(testing::readText(dir / "capped" / "metrics.json"));
  const auto& capped_probe = capped_metrics["locked_cord_probe"];
  EXPECT_EQ(capped_metrics["unsettled_sims"].get<int>(), 1) << "the seed's closure";
  EXPECT_GT(capped_probe["forward_sims"].get<int>(), 0);
  EXPECT_EQ(capped_probe["unsettled_sims"], capped_probe["forward_sims"]) << capped_probe;
  EXPECT_EQ(capped_metrics["uncertainty"]["error"], "no free parameters");
  // A summary line (stdout) or, when a locked cord holds the fit back, a note (stderr).
  EXPECT_NE(
      (capped.out + capped.err)
          .find(std::to_string(capped_probe["forward_sims"].get<int>()) + " extra closures, " +
                std::to_string(capped_probe["unsettled_sims"].get<int>()) + " unsettled"),
      std::string::npos)
      << capped.out << capped.err;
  EXPECT_NE(testing::readText(dir / "capped" / "report.md")
                .find(" reached the step cap without settling), "),
            std::string::npos);

  const auto skipped = runChordfit(fit + " --no-uncertainty --out " + quoted(dir / "skipped"));
  ASSERT_EQ(skipped.exit_code, 0) << skipped.err;
  EXPECT_EQ((skipped.out + skipped.err).find("locked cords"), std::string::npos) << skipped.out;
  EXPECT_FALSE(nlohmann::json::parse(testing::readText(dir / "skipped" / "metrics.json"))
                   .contains("locked_cord_probe"));
  EXPECT_EQ(testing::readText(dir / "skipped" / "report.md").find("## Locked cords"),
            std::string::npos);
}

// The tracings of the bundled prolapse-P2 case show a P2 flap. A fit that cannot make it says
// what to try: with every P2 cord at the upper scale bound, a higher bound; with every P2 cord
// locked, unlocking them.
TEST(FitCommand, SaysWhatToTryWhenTheTracingsProlapseWhereTheFitDoesNot) {
  TempDir dir;
  const std::filesystem::path prolapse_case =
      std::filesystem::path(CHORDFIT_CASES_DIR) / "prolapse-P2";
  const auto bounded =
      runChordfit("fit " + quoted(prolapse_case) +
                  " --scale-bounds 0.6,0.75 --no-prefit --no-uncertainty --max-sims 3 --out " +
                  quoted(dir / "bounded"));
  ASSERT_EQ(bounded.exit_code, 0) << bounded.err;
  const std::string upper = "the tracings show prolapse in P2, the fitted closure does not: ";
  EXPECT_NE(bounded.err.find("note: " + upper), std::string::npos) << bounded.err;
  EXPECT_NE(bounded.err.find("free cords there end at the upper scale bound 0.75; a higher one "
                             "(--scale-bounds 0.6,HI)"),
            std::string::npos)
      << bounded.out;
  EXPECT_NE(testing::readText(dir / "bounded" / "report.md").find(upper), std::string::npos);

  ASSERT_EQ(runChordfit("edit-cords " + quoted(prolapse_case) +
                        " --segment P2=0.75 --lock edited --out " + quoted(dir / "seed.json"))
                .exit_code,
            0);
  const auto locked =
      runChordfit("fit " + quoted(prolapse_case) + " --seed-cords " + quoted(dir / "seed.json") +
                  " --no-prefit --no-uncertainty --max-sims 3 --out " + quoted(dir / "locked"));
  ASSERT_EQ(locked.exit_code, 0) << locked.err;
  EXPECT_NE(locked.err.find(upper + "every cord there is locked"), std::string::npos) << locked.err;
}

// --params groups: a group factor's bounds keep the group's mean scale within --scale-bounds,
// so a cord below its group's mean shrinks further than the bound itself; a bound that leaves
// such a cord under 1 mm is refused before the fit (the per-cord check let it through, and the
// fit would have written a cords.json no reader takes).
TEST(FitCommand, GroupBoundsThatShrinkACordBelowOneMillimetreAreRefused) {
  TempDir dir;
  auto cords = nlohmann::json::parse(testing::readText(smallCase() / "cords.json"));
  // Every cord 30 mm long from the seed's view; all but the first lengthened to 45 mm, so the
  // first one's group has a mean scale above 1 and the first cord lies below it.
  for (std::size_t c = 0; c < cords["cords"].size(); ++c) {
    auto& cord = cords["cords"][c];
    const double rest = c == 0 ? 30.0 : 45.0;
    cord["seed_rest_length_mm"] = 30.0;
    cord["rest_length_mm"] = rest;
    cord["scale"] = rest / 30.0;
    cord["provenance"] = c == 0 ? "heuristic" : "manual";
  }
  testing::writeText(dir / "seed.json", cords.dump(1));
  // 30 mm x 0.0334 = 1.002 mm: every cord stays above 1 mm at the bound itself.
  const std::string fit = "fit " + quoted(smallCase()) + " --seed-cords " +
                          quoted(dir / "seed.json") + " --scale-bounds 0.0334,1.5 --max-sims 20 " +
                          "--no-uncertainty --quiet --out ";
  const auto groups = runChordfit(fit + quoted(dir / "groups") + " --params groups");
  EXPECT_EQ(groups.exit_code, 2) << groups.err;
  EXPECT_NE(groups.err.find("error: fit: --scale-bounds: with --params groups the lower bound "
                            "0.0334 lets cord 0 of " +
                            (dir / "seed.json").string() + " (group "),
            std::string::npos)
      << groups.err;
  EXPECT_NE(groups.err.find("shrink to 0."), std::string::npos) << groups.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "groups" / "cords.json"));
  // Per cord the same bounds are fine: the fit runs.
  const auto scales = runChordfit(fit + quoted(dir / "scales") + " --no-prefit");
  EXPECT_EQ(scales.exit_code, 0) << scales.err;
}

// convergence.csv's last row counts every closure of the fit (metrics.json's forward_sims less
// the closure written): a Ceres solve that ended on a trial it rejected (--params groups on the
// bundled case: parameter tolerance after a rejected step) left that closure out, 110 of 111.
TEST(FitCommand, ConvergenceCsvCountsEveryClosureOfTheFit) {
  TempDir dir;
  const auto r =
      runChordfit("fit " + quoted(std::filesystem::path(CHORDFIT_CASES_DIR) / "prolapse-P2") +
                  " --params groups --fd-warm --max-sims 300 --no-uncertainty --quiet --out " +
                  quoted(dir / "fit"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto metrics = nlohmann::json::parse(testing::readText(dir / "fit" / "metrics.json"));
  const auto rows = parseSimpleCsv(testing::readText(dir / "fit" / "convergence.csv"));
  ASSERT_GE(rows.size(), 2u);
  EXPECT_EQ(rows[0][5], "forward_sims");
  EXPECT_EQ(std::stoi(rows.back()[5]), metrics["forward_sims"].get<int>() - 1)
      << testing::readText(dir / "fit" / "convergence.csv");
  // The case this test is about: the last closure is a trial Ceres rejected (its cost above the
  // best so far). Should a change of the fit's path end it otherwise, the test would pass
  // without covering that case: it says so instead.
  ASSERT_EQ(rows[0][2], "cost");
  ASSERT_EQ(rows[0][3], "best_cost");
  EXPECT_GT(std::stod(rows.back()[2]), std::stod(rows.back()[3]))
      << "the fit no longer ends on a rejected trial; pick options that do";
}

// A budget too small for the kind stage (inverse/global_prefit.h) still runs the common
// factor: 8 grid + 4 refinement closures fit in 16 runs, 8 more for the kinds do not.
TEST(FitCommand, SmallBudgetKeepsTheCommonPrefitFactorAndSkipsTheKindStage) {
  TempDir dir;
  const auto metrics = fitSmallCase("--max-sims 16 --threads 2 --quiet", dir / "fit");
  ASSERT_FALSE(metrics.empty());
  const double common = metrics["prefit_factor"].get<double>();
  EXPECT_NE(common, 1.0) << "the heuristic's cords are too long: the common stage moves them";
  EXPECT_EQ(metrics["prefit_primary_factor"].get<double>(), common);
  EXPECT_EQ(metrics["prefit_secondary_factor"].get<double>(), common);
  EXPECT_FALSE(metrics["prefit_kind_ran"].get<bool>());
  EXPECT_LE(metrics["forward_sims"].get<int>(), 17);  // budget 16 + the closure written
  // The report said "per kind: primaries 0.7, secondaries 0.7" as if the stage had run.
  EXPECT_NE(testing::readText(dir / "fit" / "report.md")
                .find("; per kind: not run (--max-sims 16 leaves too few closures)"),
            std::string::npos);
}

// Every secondary locked: the kind stage has one kind to move and does not run, and the report
// says so (it printed "per kind: primaries 0.7, secondaries 0.7" as if it had).
TEST(FitCommand, ReportsAKindStageWithOneFreeKindAsNotRun) {
  TempDir dir;
  const auto cords = nlohmann::json::parse(testing::readText(smallCase() / "cords.json"));
  std::string secondaries;
  for (std::size_t i = 0; i < cords["cords"].size(); ++i)
    if (cords["cords"][i]["kind"] == "secondary")
      secondaries += (secondaries.empty() ? "" : ",") + std::to_string(i);
  ASSERT_FALSE(secondaries.empty());
  ASSERT_EQ(runChordfit("edit-cords " + quoted(smallCase()) + " --lock " + secondaries + " --out " +
                        quoted(dir / "seed.json"))
                .exit_code,
            0);
  const auto metrics = fitSmallCase(
      "--seed-cords " + quoted(dir / "seed.json") + " --max-sims 40 --no-uncertainty --quiet",
      dir / "fit");
  ASSERT_FALSE(metrics.empty());
  EXPECT_TRUE(metrics["prefit_ran"].get<bool>());
  EXPECT_FALSE(metrics["prefit_kind_ran"].get<bool>());
  EXPECT_NE(
      testing::readText(dir / "fit" / "report.md")
          .find("; per kind: not run (only one cord kind has free cords that are not manual)"),
      std::string::npos);
}

// A budget the pre-fits use up: the optimiser took no step, and the terminal, report.md and
// the missed-prolapse advice say so (they read "ceres after 23 forward runs" and blamed the
// cords and the tissue, where more --max-sims reconstructs the flap).
TEST(FitCommand, SaysWhenThePreFitsLeftTheOptimiserNoStep) {
  TempDir dir;
  const auto prolapse = std::filesystem::path(CHORDFIT_CASES_DIR) / "prolapse-P2";
  const auto r =
      runChordfit("fit " + quoted(prolapse) + " --max-sims 30 --no-uncertainty --quiet --out " +
                  quoted(dir / "fit"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("forward runs (pre-fits only; ceres took no step)"), std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("fit: ceres after"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("the fitted closure does not: ceres took no step, the budget being spent"),
            std::string::npos)
      << r.err;
  EXPECT_NE(
      testing::readText(dir / "fit" / "report.md").find("; pre-fits only; ceres took no step"),
      std::string::npos);
  EXPECT_NE(
      testing::readText(dir / "fit" / "convergence.svg").find("pre-fits only; ceres took no step"),
      std::string::npos);

  // Without pre-fits, it is not their result; and an NLopt method that evaluated a point of its
  // own ran (its first evaluation, the start, is no step).
  const auto bare = runChordfit("fit " + quoted(smallCase()) +
                                " --no-prefit --max-sims 1 --no-uncertainty --quiet --out " +
                                quoted(dir / "bare"));
  ASSERT_EQ(bare.exit_code, 0) << bare.err;
  EXPECT_NE(bare.out.find("forward run (ceres took no step)"), std::string::npos) << bare.out;
  const auto nlopt = runChordfit("fit " + quoted(smallCase()) +
                                 " --optimizer bobyqa --no-prefit --max-sims 1 --no-uncertainty "
                                 "--quiet --out " +
                                 quoted(dir / "nlopt"));
  ASSERT_EQ(nlopt.exit_code, 0) << nlopt.err;
  EXPECT_NE(nlopt.out.find("(bobyqa took no step)"), std::string::npos) << nlopt.out;
  const auto stepped = runChordfit("fit " + quoted(smallCase()) +
                                   " --optimizer bobyqa --no-prefit --max-sims 6 --no-uncertainty "
                                   "--quiet --out " +
                                   quoted(dir / "stepped"));
  ASSERT_EQ(stepped.exit_code, 0) << stepped.err;
  EXPECT_NE(stepped.out.find("fit: bobyqa after"), std::string::npos) << stepped.out;
}

// Finite-difference options given to an NLopt fit, which takes no derivatives: a note saying
// what they still reach (the uncertainty's Jacobian, or nothing without it).
TEST(FitCommand, NotesFiniteDifferenceOptionsAnNloptFitDoesNotUse) {
  TempDir dir;
  for (const bool uncertainty : {true, false}) {
    const auto r = runChordfit("fit " + quoted(smallCase()) +
                               " --optimizer bobyqa --fd-step 0.02 --fd-warm --max-sims 3 "
                               "--no-prefit --quiet" +
                               (uncertainty ? "" : " --no-uncertainty") + " --out " +
                               quoted(dir / (uncertainty ? "u" : "n")));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string reach =
        uncertainty ? "the steps after the fit (the uncertainty's Jacobian, the locked-cord probe)"
                    : "Ceres' Jacobians, so on nothing here (--no-uncertainty)";
    for (const std::string option : {"--fd-step", "--fd-warm"})
      EXPECT_NE(r.err.find("note: fit: " + option + " acts only on " + reach +
                           " with --optimizer bobyqa"),
                std::string::npos)
          << r.err;
    EXPECT_EQ(r.err.find("--fd-slack-closures acts"), std::string::npos) << "not given";
  }
}

// Options that only move PM tips, given to a fit that does not: a note, and the fit runs; the
// report says why a pre-fit did not run (it said "segment pre-fit: no change").
TEST(FitCommand, NotesTipOptionsWithoutTipsAndReportsPrefitsThatDidNotRun) {
  TempDir dir;
  const auto r = runChordfit("fit " + quoted(smallCase()) +
                             " --params groups --tip-box 3 --max-sims 20 --quiet --no-uncertainty"
                             " --out " +
                             quoted(dir / "fit"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: fit: --tip-box acts only with --params scales+tips (this fit: "
                       "--params groups)"),
            std::string::npos)
      << r.err;
  const std::string report = testing::readText(dir / "fit" / "report.md");
  EXPECT_NE(report.find("- segment pre-fit: not run with --params groups"), std::string::npos)
      << report;
  const auto off = runChordfit("fit " + quoted(smallCase()) +
                               " --no-prefit --max-sims 20 --quiet --no-uncertainty --out " +
                               quoted(dir / "off"));
  ASSERT_EQ(off.exit_code, 0) << off.err;
  const std::string off_report = testing::readText(dir / "off" / "report.md");
  EXPECT_NE(off_report.find("- global pre-fit: disabled (--no-prefit)"), std::string::npos)
      << off_report;
  EXPECT_NE(off_report.find("- segment pre-fit: disabled (--no-prefit)"), std::string::npos);
}

// With --params groups every cord shares its group's SD; a cord slack in the fit is still not
// determined by the data (they bound it from below only). All 32 counted before.
TEST(FitCommand, GroupFitsCountOnlyTautCordsAsDetermined) {
  TempDir dir;
  const auto metrics = fitSmallCase("--params groups --max-sims 40 --quiet", dir / "fit");
  ASSERT_FALSE(metrics.empty());
  ASSERT_TRUE(metrics["uncertainty"].contains("identified_cords")) << metrics["uncertainty"];
  const std::string report = testing::readText(dir / "fit" / "report.md");
  std::smatch slack;
  ASSERT_TRUE(std::regex_search(report, slack, std::regex("([0-9]+) of ([0-9]+) cords are slack")));
  const int taut = std::stoi(slack[2]) - std::stoi(slack[1]);
  EXPECT_GT(std::stoi(slack[1]), 0) << "the heuristic's small case has slack cords";
  EXPECT_LE(metrics["uncertainty"]["identified_cords"].get<int>(), taut);
  EXPECT_NE(report.find("- slack release: not run with --params groups"), std::string::npos);
  // A slack cord's SD is its group's, and the table says so.
  EXPECT_NE(report.find(" (group's; slack) |"), std::string::npos) << report;
  EXPECT_NE(report.find(" (group's) | fitted |"), std::string::npos)
      << "the sensitivity is the group's too";
}

// The whole fit (pre-fits, optimiser, slack release, uncertainty, the closure written) gives
// the same files with 1 or 2 threads, byte for byte, but for the wall times and the thread
// count: metrics.json's seconds and threads, convergence.csv's elapsed column and report.md's
// "fit time: ..., threads: ..." line. The budget reaches the optimiser (its Jacobians are
// where the threads split the work).
TEST(FitCommand, GivesTheSameFilesWithOneOrTwoThreads) {
  TempDir dir;
  for (const char* threads : {"1", "2"})
    ASSERT_FALSE(
        fitSmallCase(std::string("--max-sims 100 --quiet --threads ") + threads, dir / threads)
            .empty());
  const auto one = directorySnapshot(dir / "1");
  const auto two = directorySnapshot(dir / "2");
  std::vector<std::string> names_one, names_two;
  for (const auto& entry : one) names_one.push_back(entry.first);
  for (const auto& entry : two) names_two.push_back(entry.first);
  ASSERT_EQ(names_one, names_two);
  for (const char* file : {"cords.json", "closed.ply", "closed.vtk", "uncertainty.csv",
                           "convergence.svg", "sections.svg", "enface.svg"})
    EXPECT_EQ(one.count(file), 1u) << file;
  const std::set<std::string> timed = {"metrics.json", "convergence.csv", "report.md"};
  for (const auto& [name, bytes] : one) {
    if (timed.count(name) == 0) {
      EXPECT_TRUE(bytes == two.at(name)) << name << " differs";
    }
  }

  auto stripped = [](const std::string& text) {
    auto m = nlohmann::json::parse(text);
    for (const char* key : {"fit_seconds", "sim_seconds", "threads"}) {
      EXPECT_TRUE(m.contains(key)) << key;
      m.erase(key);
    }
    EXPECT_TRUE(m["uncertainty"].contains("seconds"));
    m["uncertainty"].erase("seconds");
    return m;
  };
  EXPECT_EQ(stripped(one.at("metrics.json")), stripped(two.at("metrics.json")));

  // The rows without their elapsed time (the last column); Ceres made steps.
  auto rows = [](const std::string& csv) {
    std::string kept;
    std::istringstream in(csv);
    for (std::string line; std::getline(in, line);) kept += line.substr(0, line.rfind(',')) + "\n";
    return kept;
  };
  const std::string& csv = one.at("convergence.csv");
  ASSERT_EQ(
      csv.rfind("stage,iteration,cost,best_cost,mean_deviation_mm,forward_sims,elapsed_s\n", 0), 0u)
      << csv;
  ASSERT_NE(csv.find("\nceres,1,"), std::string::npos) << csv;
  EXPECT_EQ(rows(csv), rows(two.at("convergence.csv")));

  const std::regex times("fit time: [0-9.]+ s, threads: [12]\n");
  const std::string& report = one.at("report.md");
  ASSERT_EQ(std::distance(std::sregex_iterator(report.begin(), report.end(), times),
                          std::sregex_iterator()),
            1)
      << report;
  EXPECT_EQ(std::regex_replace(report, times, ""),
            std::regex_replace(two.at("report.md"), times, ""));
}

// On prolapse-P2 seed 1 with a 3 mm case mesh, a warm-started perturbation settles on another
// branch than the full closure: the warm Jacobian mispredicts, Ceres rejected its steps and,
// before the switch to full closures, stopped at AvgD 0.51 mm where a fit on full closures
// reaches 0.29. With --fd-warm the solve now goes on with full closures after two rejected
// steps in a row, and reaches the full fit's result.
TEST(FitCommand, WarmDifferencesThatMispredictGiveWayToFullClosures) {
  TempDir dir;
  auto r = runChordfit("make-case --preset prolapse-P2 --seed 1 --edge 3 --quiet --out " +
                       quoted(dir / "case"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = runChordfit("fit " + quoted(dir / "case") +
                  " --fd-warm --max-sims 250 --no-uncertainty --quiet --out " +
                  quoted(dir / "fit"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto metrics = nlohmann::json::parse(testing::readText(dir / "fit" / "metrics.json"));
  EXPECT_LT(metrics["mean_mm"].get<double>(), 0.35) << metrics["termination"];
  EXPECT_LE(metrics["forward_sims"].get<int>(), 250);
  const std::string termination = metrics["termination"];
  EXPECT_NE(termination.find("rejected on warm-started differences"), std::string::npos)
      << termination;
  EXPECT_NE(testing::readText(dir / "fit" / "convergence.csv").find("\nceres-full,"),
            std::string::npos)
      << "the full-closure stage has its own rows";
  EXPECT_NE(testing::readText(dir / "fit" / "convergence.svg").find(">ceres-full: full closures<"),
            std::string::npos)
      << "and its own markers and legend entry";
  EXPECT_TRUE(metrics["fd_switched_to_full_closures"].get<bool>());
  EXPECT_NE(testing::readText(dir / "fit" / "report.md").find("until Ceres rejected two steps"),
            std::string::npos);

  // With too small a budget for a full-closure Jacobian and a step, the warm solve goes on
  // with trial steps instead of stopping.
  r = runChordfit("fit " + quoted(dir / "case") +
                  " --fd-warm --max-sims 100 --no-uncertainty --quiet --out " +
                  quoted(dir / "small"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto small = nlohmann::json::parse(testing::readText(dir / "small" / "metrics.json"));
  EXPECT_FALSE(small["fd_switched_to_full_closures"].get<bool>()) << small["termination"];
  EXPECT_NE(small["termination"].get<std::string>().find(
                "budget of 99 forward runs too small for the Jacobian at the last accepted step"),
            std::string::npos)
      << small["termination"];
}

// A seed whose closure diverges (settings inside their ranges can still break a run) is a
// simulation failure: exit 3, nothing written.
TEST(FitCommand, ADivergingSeedClosureExitsWith3AndWritesNothing) {
  TempDir dir;
  std::filesystem::copy(smallCase(), dir / "case", std::filesystem::copy_options::recursive);
  auto c = nlohmann::json::parse(testing::readText(dir / "case" / "case.json"));
  c["simulation"] = nlohmann::json::parse(testing::kDivergingSimulationJson);
  testing::writeText(dir / "case" / "case.json", c.dump());
  const auto r = runChordfit("fit " + quoted(dir / "case") + " --max-sims 20 --quiet --out " +
                             quoted(dir / "fit"));
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("seed closure failed: simulation diverged"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "fit" / "cords.json"));
}

// A fit that fails (a diverging seed closure, exit 3) or is refused (exit 2) in a directory
// holding an earlier run's outputs leaves every file there as it was, and no staging
// directory behind.
TEST(FitCommand, AFailedOrRefusedFitLeavesAnEarlierRunsOutputsAsTheyWere) {
  TempDir dir;
  const auto earlier =
      fitSmallCase("--no-prefit --no-uncertainty --max-sims 1 --quiet", dir / "fit");
  ASSERT_FALSE(earlier.empty());
  const auto before = directorySnapshot(dir / "fit");
  ASSERT_EQ(before.count("cords.json"), 1u);
  ASSERT_EQ(before.count("report.md"), 1u);

  std::filesystem::copy(smallCase(), dir / "case", std::filesystem::copy_options::recursive);
  auto c = nlohmann::json::parse(testing::readText(dir / "case" / "case.json"));
  c["simulation"] = nlohmann::json::parse(testing::kDivergingSimulationJson);
  testing::writeText(dir / "case" / "case.json", c.dump());
  const auto diverged = runChordfit("fit " + quoted(dir / "case") +
                                    " --max-sims 20 --quiet --out " + quoted(dir / "fit"));
  EXPECT_EQ(diverged.exit_code, 3) << diverged.out << diverged.err;
  auto after = directorySnapshot(dir / "fit");
  EXPECT_TRUE(after == before) << "a diverging fit changed the earlier outputs";
  EXPECT_TRUE(stagingEntries(after).empty()) << stagingEntries(after).front();

  const auto refused = runChordfit("fit " + quoted(smallCase()) + " --optimizer newton --out " +
                                   quoted(dir / "fit"));
  EXPECT_EQ(refused.exit_code, 2) << refused.out << refused.err;
  after = directorySnapshot(dir / "fit");
  EXPECT_TRUE(after == before) << "a refused fit changed the earlier outputs";
  EXPECT_TRUE(stagingEntries(after).empty()) << stagingEntries(after).front();
}

// The pre-fit's budget check counts the closures its common stage runs: the seed, 8 grid
// factors (1 is the seed's), 4 refinements and one closure left for the optimiser fit in 14.
TEST(FitCommand, ACommonPrefitThatJustFitsTheBudgetRuns) {
  TempDir dir;
  const auto metrics =
      fitSmallCase("--max-sims 14 --threads 2 --quiet --no-uncertainty", dir / "fit");
  ASSERT_FALSE(metrics.empty());
  EXPECT_NE(metrics["prefit_factor"].get<double>(), 1.0);
  EXPECT_LE(metrics["forward_sims"].get<int>(), 15);  // budget 14 + the closure written
}

// A central difference at the lower scale bound closes lower - step; at or below zero every
// Jacobian there would fail.
TEST(FitCommand, RejectsAFiniteDifferenceStepNotBelowTheLowerScaleBound) {
  const std::string err = refusedFitMessage("--scale-bounds 0.5,1.5 --fd-step 0.5");
  EXPECT_NE(err.find("error: fit: --fd-step: 0.5 is not below the lower scale bound 0.5"),
            std::string::npos)
      << err;
}

// `edit-cords SMALL_CASE EDITS --out FILE`, expected to succeed.
void editSmallCase(const std::string& edits, const std::filesystem::path& file) {
  const auto r =
      runChordfit("edit-cords " + quoted(smallCase()) + " " + edits + " --out " + quoted(file));
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

// A seed outside the scale bounds starts where the bounds put it, for the pre-fits and the
// optimiser alike (found by a probe of the fit):
//   - every cord at 1.6 (all manual: no pre-fit): Ceres refused to start, counting a Jacobian
//     of every parameter ("66 runs, 58 left") where the clamped start's taut cords needed 6,
//     and wrote the clamped start, worse than the seed, without a convergence.csv row for it;
//   - one manual cord at 0.06 of its length: the pre-fits closed the valve with it as given (every
//     closure ran to the step cap) and fitted their factors to a valve the optimiser never saw.
TEST(FitCommand, ASeedOutsideTheBoundsStartsClampedForThePrefitsAndTheOptimiser) {
  TempDir dir;
  editSmallCase("--all 1.6", dir / "long.json");
  auto metrics = fitSmallCase(
      "--seed-cords " + quoted(dir / "long.json") + " --max-sims 60 --no-uncertainty --quiet",
      dir / "long");
  ASSERT_FALSE(metrics.empty());
  EXPECT_LT(metrics["mean_mm"].get<double>(), metrics["initial_mean_mm"].get<double>())
      << metrics["termination"];
  // Every cord manual: no pre-fit runs, and Ceres closes the clamped start and goes on.
  auto rows = parseSimpleCsv(testing::readText(dir / "long" / "convergence.csv"));
  ASSERT_GE(rows.size(), 4u);
  EXPECT_EQ(rows[2][0], "ceres");
  EXPECT_EQ(rows[3][0], "ceres");
  EXPECT_EQ(rows[3][1], "1") << "Ceres made a step";
  EXPECT_EQ(rows.back()[5], std::to_string(metrics["forward_sims"].get<int>() - 1));

  editSmallCase("--cord 0=0.06", dir / "short.json");
  metrics = fitSmallCase(
      "--seed-cords " + quoted(dir / "short.json") + " --max-sims 60 --no-uncertainty --quiet",
      dir / "short");
  ASSERT_FALSE(metrics.empty());
  rows = parseSimpleCsv(testing::readText(dir / "short" / "convergence.csv"));
  ASSERT_GE(rows.size(), 4u);
  EXPECT_EQ(rows[2][0], "clamped");
  EXPECT_EQ(rows[3][0], "prefit");
  // The pre-fit improves on the clamped start it began from (it began from the seed as given,
  // and its closures did not settle).
  EXPECT_LT(std::stod(rows[3][2]), std::stod(rows[2][2]));
  EXPECT_LT(metrics["unsettled_sims"].get<int>(), 5);
}

// A budget below one Jacobian and a step: Ceres does not run, and convergence.csv has no row
// for it (it repeated the pre-fit's closure as "ceres,0").
TEST(FitCommand, ABudgetTooSmallForCeresAddsNoCeresRow) {
  TempDir dir;
  const auto metrics = fitSmallCase("--max-sims 20 --no-uncertainty --quiet", dir / "fit");
  ASSERT_FALSE(metrics.empty());
  const std::string csv = testing::readText(dir / "fit" / "convergence.csv");
  EXPECT_EQ(csv.find("\nceres,"), std::string::npos) << csv;
}

// Per cord the bounds multiply the seed rest length: a manual cord edited to 0.045 of it (1.1 mm)
// starts clamped at 0.7 of 25 mm, and the fit was refused as if 0.7 applied to 1.1 mm.
TEST(FitCommand, ChecksTheScaleBoundsOnTheSeedRestLengthsPerCord) {
  TempDir dir;
  editSmallCase("--cord 0=0.045", dir / "tiny.json");
  const auto metrics = fitSmallCase(
      "--seed-cords " + quoted(dir / "tiny.json") + " --max-sims 20 --no-uncertainty --quiet",
      dir / "fit");
  ASSERT_FALSE(metrics.empty());
  EXPECT_EQ(metrics["scale_bounds"], nlohmann::json({0.7, 1.5})) << "the default bounds";
  // The seed as given, then the start clamped into the bounds (a closure of its own).
  const auto rows = parseSimpleCsv(testing::readText(dir / "fit" / "convergence.csv"));
  ASSERT_GE(rows.size(), 3u);
  EXPECT_EQ(rows[1][0], "seed");
  EXPECT_EQ(rows[2][0], "clamped");
  EXPECT_EQ(rows[2][5], "2");
  // Every fitted cord within [0.7, 1.5] of its seed rest length (round-off aside), the tiny
  // one included.
  const auto fitted = nlohmann::json::parse(testing::readText(dir / "fit" / "cords.json"));
  ASSERT_EQ(fitted["cords"].size(), 32u);
  for (std::size_t c = 0; c < fitted["cords"].size(); ++c) {
    const auto& cord = fitted["cords"][c];
    const double scale =
        cord["rest_length_mm"].get<double>() / cord["seed_rest_length_mm"].get<double>();
    EXPECT_GE(scale, 0.7 - 1e-12) << "cord " << c;
    EXPECT_LE(scale, 1.5 + 1e-12) << "cord " << c;
    EXPECT_NEAR(cord["scale"].get<double>(), scale, 1e-12) << "cord " << c;
  }
}

// Closures that reached the step cap are in report.md, not only on the terminal.
TEST(FitCommand, ReportSaysWhenClosuresDidNotSettle) {
  TempDir dir;
  const auto metrics =
      fitSmallCase("--set max_steps=150 --max-sims 20 --no-uncertainty --quiet", dir / "fit");
  ASSERT_FALSE(metrics.empty());
  ASSERT_GT(metrics["unsettled_sims"].get<int>(), 0);
  const std::string report = testing::readText(dir / "fit" / "report.md");
  EXPECT_NE(report.find("- unsettled: " + std::to_string(metrics["unsettled_sims"].get<int>()) +
                        " of the fit's"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("the fit's best closure did not settle"), std::string::npos) << report;
}

}  // namespace
}  // namespace chordfit
