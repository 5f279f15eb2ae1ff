// The benchmark pipeline (experiments/run_experiments, issue "Benchmark experiments"): the
// plan and its shards, merge from per-job results, and a small real run (heuristic and truth
// closures of the smoke case) that must give the same tables in one piece and in two shards.
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include "tests/test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;
using testing::readText;
using testing::TempDir;
using testing::writeText;

// The runner is built beside chordfit: <build>/tools/chordfit -> <build>/experiments/.
fs::path runnerPath() {
  return fs::path(CHORDFIT_EXE).parent_path().parent_path() / "experiments" / "run_experiments";
}

using testing::quoted;

testing::CommandResult runRunner(const std::string& arguments) {
  return testing::runProgram(runnerPath(), arguments);
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> result;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) result.push_back(line);
  return result;
}

std::vector<std::string> cells(const std::string& line) {
  std::vector<std::string> result;
  std::istringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) result.push_back(cell);
  if (!line.empty() && line.back() == ',') result.push_back("");
  return result;
}

// The cells of a Markdown table row "| a | b |": "", " a ", " b " (leading empty cell kept,
// so cell k is the k-th column).
std::vector<std::string> markdownCells(const std::string& line) {
  std::vector<std::string> result;
  std::istringstream in(line);
  for (std::string cell; std::getline(in, cell, '|');) result.push_back(cell);
  return result;
}

// Runs the experiment tool `tool` with each of `cases`' arguments and expects a usage error
// (exit 2) whose text names the problem (the paired message).
void expectUsageErrors(const fs::path& tool,
                       const std::vector<std::pair<std::string, std::string>>& cases) {
  for (const auto& [arguments, message] : cases) {
    const testing::CommandResult r = testing::runProgram(tool, arguments);
    EXPECT_EQ(r.exit_code, 2) << arguments;
    EXPECT_NE(r.err.find(message), std::string::npos) << arguments << ": " << r.err;
  }
}

class ExperimentsPipeline : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(runnerPath()))
        << runnerPath() << " is not built (cmake --build BUILD --target run_experiments)";
  }
};

TEST_F(ExperimentsPipeline, FullPlanIsTheDefaultAndHasEveryPresetSeedAndMethod) {
  const auto r = runRunner("list");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::set<std::string> jobs;
  int cases = 0;
  for (const std::string& line : lines(r.out)) {
    if (line.rfind("case ", 0) == 0) ++cases;
    if (line.rfind("job  ", 0) == 0) {
      EXPECT_TRUE(jobs.insert(line.substr(5)).second) << line;
    }
  }
  // 7 presets x 3 seeds, plus 3 noise and 2 plane-count variants of prolapse-P2 seed 1.
  EXPECT_EQ(cases, 21 + 5);
  for (const char* preset : {"normal-1", "normal-2", "prolapse-P2", "prolapse-A2", "prolapse-P3",
                             "bileaflet", "flail-P2"}) {
    for (int seed = 1; seed <= 3; ++seed) {
      const std::string id = std::string(preset) + "_s" + std::to_string(seed);
      for (const char* method : {"heuristic", "fit_groups_ceres", "fit_scales_ceres",
                                 "fit_scales-tips_ceres", "fit_scales-tissue_ceres", "truth"}) {
        EXPECT_TRUE(jobs.count(id + "__" + method)) << id << " " << method;
      }
    }
  }
  for (const char* optimizer : {"bobyqa", "cobyla", "sbplx", "crs2"}) {
    EXPECT_TRUE(jobs.count(std::string("prolapse-A2_s1__fit_scales_") + optimizer)) << optimizer;
    EXPECT_FALSE(jobs.count(std::string("normal-1_s1__fit_scales_") + optimizer))
        << "the optimiser comparison is on the pathological presets";
  }
  EXPECT_TRUE(jobs.count("prolapse-P2_s1_noise0__fit_scales_ceres"));
  EXPECT_TRUE(jobs.count("prolapse-P2_s1_noise1__truth"));
  EXPECT_TRUE(jobs.count("prolapse-P2_s1_planes12__heuristic"));
}

TEST_F(ExperimentsPipeline, ReducedPlanCoversEveryPresetAtSeedOne) {
  const auto r = runRunner("list --plan reduced");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int cases = 0;
  std::set<std::string> jobs;
  for (const std::string& line : lines(r.out)) {
    if (line.rfind("case ", 0) == 0) ++cases;
    if (line.rfind("job  ", 0) == 0) jobs.insert(line.substr(5));
  }
  EXPECT_EQ(cases, 7 + 5);  // every preset at seed 1, plus the sweep variants
  EXPECT_TRUE(jobs.count("bileaflet_s1__fit_scales-tips_ceres"));
  EXPECT_TRUE(jobs.count("prolapse-P2_s1__fit_scales_crs2"));
  EXPECT_FALSE(jobs.count("prolapse-A2_s1__fit_scales_crs2"));
  EXPECT_FALSE(jobs.count("normal-1_s2__heuristic"));
  EXPECT_EQ(runRunner("list --plan most").exit_code, 2);
  const auto none = runRunner("list --methods nosuch");
  EXPECT_EQ(none.exit_code, 2) << "a filter matching no job is a usage error";
  EXPECT_NE(none.err.find("--methods: \"nosuch\" is not one of the plan's"), std::string::npos)
      << none.err;
  const auto disjoint = runRunner("list --presets normal-1 --cases prolapse-P2_s1");
  EXPECT_EQ(disjoint.exit_code, 2);
  EXPECT_NE(disjoint.err.find("no job matches all of them together"), std::string::npos)
      << disjoint.err;
}

// --methods names methods exactly (a bare name was a prefix: fit_scales selected seven methods,
// the tips, tissue and NLopt fits too); a Ceres fit may leave out its _ceres, and NAME* is the
// prefix. The run says which methods it selected.
TEST_F(ExperimentsPipeline, MethodsAreExactNamesOrAnExplicitPrefix) {
  auto methodsOf = [](const std::string& out) {
    std::set<std::string> methods;
    for (const std::string& line : lines(out)) {
      if (line.rfind("job  ", 0) == 0) methods.insert(line.substr(line.find("__") + 2));
    }
    return methods;
  };
  auto r = runRunner("list --methods fit_scales");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(methodsOf(r.out), std::set<std::string>{"fit_scales_ceres"});
  EXPECT_NE(r.err.find("--methods selects 1 method(s): fit_scales_ceres\n"), std::string::npos)
      << r.err;
  r = runRunner("list --methods fit_scales_ceres");
  EXPECT_EQ(methodsOf(r.out), std::set<std::string>{"fit_scales_ceres"});
  r = runRunner("list --methods 'fit_scales_*'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(methodsOf(r.out),
            (std::set<std::string>{"fit_scales_ceres", "fit_scales_bobyqa", "fit_scales_cobyla",
                                   "fit_scales_sbplx", "fit_scales_crs2"}));
  EXPECT_NE(r.err.find("--methods selects 5 method(s): "), std::string::npos) << r.err;
  r = runRunner("list --methods 'fit*'");
  EXPECT_EQ(methodsOf(r.out).size(), 8u) << r.out;
  // The documented commands (experiments/README.md, docs/fitting.md) select what they did.
  r = runRunner("list --methods fit_groups,fit_scales_ceres,fit_scales-tips,fit_scales-tissue");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(methodsOf(r.out),
            (std::set<std::string>{"fit_groups_ceres", "fit_scales_ceres", "fit_scales-tips_ceres",
                                   "fit_scales-tissue_ceres"}));
  r = runRunner("list --methods heuristic,truth,fit_scales_ceres");
  EXPECT_EQ(methodsOf(r.out), (std::set<std::string>{"heuristic", "truth", "fit_scales_ceres"}));
  // A bare start of a name is no longer a selection: an error that says how to ask for one.
  r = runRunner("list --methods fit");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--methods: \"fit\" is not one of the plan's: fit_groups_ceres, "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("NAME* selects every method starting with NAME"), std::string::npos)
      << r.err;
  r = runRunner("list --methods 'nosuch*'");
  EXPECT_EQ(r.exit_code, 2) << r.err;
}

TEST_F(ExperimentsPipeline, ShardsPartitionThePlan) {
  const auto whole = runRunner("list");
  ASSERT_EQ(whole.exit_code, 0);
  std::multiset<std::string> from_shards;
  for (int i = 1; i <= 3; ++i) {
    const auto r = runRunner("list --shard " + std::to_string(i) + "/3");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto shard_lines = lines(r.out);
    EXPECT_LT(shard_lines.size(), lines(whole.out).size() / 2) << "shard " << i;
    from_shards.insert(shard_lines.begin(), shard_lines.end());
  }
  const auto all = lines(whole.out);
  EXPECT_EQ(from_shards, std::multiset<std::string>(all.begin(), all.end()));
}

TEST_F(ExperimentsPipeline, RejectsBadArguments) {
  auto r = runRunner("run --shard 3/2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--shard: expected i/N"), std::string::npos) << r.err;
  r = runRunner("frobnicate");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown command \"frobnicate\""), std::string::npos) << r.err;
  r = runRunner("merge --shard 1/2");
  EXPECT_EQ(r.exit_code, 2);
  r = runRunner("list --methods nothing-like-this");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--methods"), std::string::npos) << r.err;
  for (const char* edge : {"0", "0.5", "9"}) {  // make-case's range is [1, 5] mm
    r = runRunner(std::string("list --edge ") + edge);
    EXPECT_EQ(r.exit_code, 2) << edge;
    EXPECT_NE(r.err.find("--edge: expected a length in [1, 5] mm"), std::string::npos) << r.err;
  }
  // A typo in a list used to drop that item silently.
  r = runRunner("list --presets normal-1,nosuch");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--presets: \"nosuch\" is not one of the plan's: bileaflet, "),
            std::string::npos)
      << r.err;
  r = runRunner("list --seeds 1,7");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--seeds: \"7\" is not one of the plan's: 1, 2, 3"), std::string::npos)
      << r.err;
  // A mistyped --results used to be created and filled with empty tables.
  TempDir empty;
  r = runRunner("merge --results " + quoted(empty / "nowhere"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nowhere/jobs: no such directory"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(empty / "nowhere"));
  r = runRunner("list --plan most");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--plan: expected full, reduced or smoke"), std::string::npos) << r.err;
  // An option given twice took its last value without a word.
  r = runRunner("list --smoke --plan full");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("the plan is given twice (--plan, --smoke)"), std::string::npos) << r.err;
  r = runRunner("list --edge 2 --edge 3");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--edge is given twice"), std::string::npos) << r.err;
  // --smoke beside --plan smoke is the same plan twice: it was refused as a conflict.
  for (const char* both : {"--smoke --plan smoke", "--plan smoke --smoke"}) {
    r = runRunner(std::string("list ") + both);
    EXPECT_EQ(r.exit_code, 0) << both << ": " << r.err;
    EXPECT_EQ(r.out, runRunner("list --smoke").out) << both;
  }
  // A switch of another command was ignored without a word.
  r = runRunner("list --smoke --force --no-timing");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: --force applies to run and all; list ignores it"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("note: --no-timing applies to merge and all; list ignores it"),
            std::string::npos)
      << r.err;
  for (const char* bounds : {"0.6", "1.5,0.7", "0,1.5", "0.6,1.5x"}) {
    r = runRunner(std::string("list --scale-bounds ") + bounds);
    EXPECT_EQ(r.exit_code, 2) << bounds;
    EXPECT_NE(r.err.find("--scale-bounds: expected LO,HI"), std::string::npos) << r.err;
  }
  // A case source that does not exist used to be ignored (every case generated, exit 0).
  r = runRunner("run --smoke --methods heuristic --case-source " + quoted(empty / "no-cases") +
                " --work " + quoted(empty / "work") + " --results " + quoted(empty / "results"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--case-source " + (empty / "no-cases").string() + ": no such directory"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(empty / "work")) << "nothing ran";
  writeText(empty / "a-file", "");
  r = runRunner("list --case-source " + quoted(empty / "a-file"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("a-file: not a directory"), std::string::npos) << r.err;
  r = runRunner("list --cases no-such-case_s1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--cases"), std::string::npos) << r.err;
}

// The default results are the build's source tree, not the working directory: --help used to
// say "experiments/results", which a copied binary run elsewhere does not write to.
TEST_F(ExperimentsPipeline, HelpPrintsTheDefaultPathsInFull) {
  const auto r = runRunner("--help");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path source = CHORDFIT_SOURCE_DIR;
  EXPECT_NE(r.out.find((source / "experiments" / "results").string()), std::string::npos) << r.out;
  EXPECT_NE(r.out.find((source / "experiments" / "work").string()), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(std::string(CHORDFIT_EXE)), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("smoke/results"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("(default: experiments/results)"), std::string::npos) << r.out;
}

TEST_F(ExperimentsPipeline, CasesAndEdgeSelectWhatRuns) {
  const auto r = runRunner("list --cases prolapse-P2_s2 --edge 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int cases = 0, jobs = 0;
  for (const std::string& line : lines(r.out)) {
    if (line.rfind("case ", 0) == 0) {
      ++cases;
      EXPECT_NE(line.find("prolapse-P2_s2"), std::string::npos) << line;
      EXPECT_NE(line.find("edge 2"), std::string::npos) << line;
    }
    jobs += line.rfind("job  prolapse-P2_s2__", 0) == 0;
  }
  EXPECT_EQ(cases, 1);
  EXPECT_EQ(jobs, 6);  // the Table 1 methods of one case, with the tissue pre-fit
}

// The case options a job result records (experiment_jobs.cpp): the smoke plan's case by default.
struct FixtureCase {
  std::string id = "normal-1_s2";
  double edge_mm = 3.0;
  int planes = 3;
  double noise_mm = 0.3;
};

// A job result as run_experiments writes it, with made-up numbers (test fixture).
nlohmann::json fixtureResult(const FixtureCase& c, const std::string& method, double mean_mm,
                             const std::vector<std::pair<double, double>>& cords) {
  nlohmann::json metrics = {{"area_mm2", 900.0},
                            {"min_mm", 0.0},
                            {"median_mm", mean_mm},
                            {"max_mm", 2 * mean_mm},
                            {"mean_mm", mean_mm},
                            {"sd_mm", 0.1},
                            {"prolapse_reconstructed", false},
                            {"prolapse_segments", {"A1"}},
                            {"tracing_prolapse_segments", nlohmann::json::array()}};
  nlohmann::json rows = nlohmann::json::array();
  for (std::size_t i = 0; i < cords.size(); ++i) {
    rows.push_back({{"index", i},
                    {"segment", "P2"},
                    {"kind", "primary"},
                    {"ruptured", false},
                    {"plane_distance_mm", cords[i].first},
                    {"rest_length_mm", 10.0 * (1 + cords[i].second)},
                    {"true_rest_length_mm", 10.0},
                    {"relative_error", cords[i].second},
                    {"taut_in_truth", i % 2 == 0}});  // every other cord taut
  }
  nlohmann::json r = {{"job", c.id + "__" + method},
                      {"case", c.id},
                      {"method", method},
                      {"metrics", metrics},
                      {"forward_sims", 1},
                      {"wall_seconds", 1.5},
                      {"cords", rows},
                      {"revision", "abc1234"},
                      {"edge_mm", c.edge_mm},
                      {"planes", c.planes},
                      {"noise_mm", c.noise_mm},
                      {"dropout", 0.1}};
  if (method == "truth") r["noise_floor"] = metrics;
  return r;
}

nlohmann::json fixtureResult(const std::string& method, double mean_mm,
                             const std::vector<std::pair<double, double>>& cords) {
  return fixtureResult(FixtureCase{}, method, mean_mm, cords);
}

// The heuristic, per-cord fit and truth results of a sensitivity case of the full plan (edge
// 2.5 mm), the fit's AvgD `fit_mm`, in dir/jobs.
void writeSweepCase(const fs::path& dir, const FixtureCase& c, double fit_mm) {
  writeText(dir / "jobs" / (c.id + "__heuristic.json"),
            fixtureResult(c, "heuristic", 2.0, {{0.5, 0.2}}).dump());
  nlohmann::json fit = fixtureResult(c, "fit_scales_ceres", fit_mm, {{0.5, 0.05}});
  fit["max_sims"] = 300;
  fit["convergence"] = {{"forward_sims", {1, 2}}, {"mean_mm", {2.0, fit_mm}}};
  writeText(dir / "jobs" / (c.id + "__fit_scales_ceres.json"), fit.dump());
  writeText(dir / "jobs" / (c.id + "__truth.json"),
            fixtureResult(c, "truth", 0.2, {{0.5, 0.0}}).dump());
}

TEST_F(ExperimentsPipeline, MergeTabulatesTheJobResultsItFindsAndListsTheMissingOnes) {
  TempDir dir;
  writeText(dir / "jobs" / "normal-1_s2__heuristic.json",
            fixtureResult("heuristic", 1.25, {{0.5, 0.10}, {0.8, -0.30}, {4.0, 0.02}}).dump());
  writeText(dir / "jobs" / "normal-1_s2__truth.json",
            fixtureResult("truth", 0.40, {{0.5, 0.0}}).dump());
  auto r = runRunner("merge --smoke --results " + quoted(dir.path()));
  EXPECT_EQ(r.exit_code, 1) << "fit jobs have no result";
  EXPECT_NE(r.err.find("normal-1_s2__fit_scales_ceres"), std::string::npos) << r.err;

  const auto table = lines(readText(dir / "table1.csv"));
  ASSERT_EQ(table.size(), 4u) << readText(dir / "table1.csv");  // header, heuristic, truth, floor
  EXPECT_EQ(cells(table[1])[3], "heuristic");
  EXPECT_EQ(cells(table[1])[9], "1.2500");
  EXPECT_EQ(cells(table[1])[11], "no");
  EXPECT_EQ(cells(table[1])[12], "") << "the fixture has no section list";
  EXPECT_EQ(cells(table[1])[13], "A1");
  EXPECT_EQ(cells(table[2])[3], "truth");
  EXPECT_EQ(cells(table[3])[4], "noise floor");
  EXPECT_EQ(cells(table[3])[15], "") << "the noise floor took no forward simulation of ours";
  const std::string md = readText(dir / "table1.md");
  EXPECT_NE(md.find("**Missing**"), std::string::npos);
  EXPECT_NE(md.find("`normal-1_s2__fit_groups_ceres`"), std::string::npos);
  EXPECT_EQ(md.find("manual-like |"), std::string::npos) << "no row for a missing job";
  EXPECT_NE(readText(dir / "acceptance.md")
                .find("**Not judged** (no heuristic or fit result): normal-1_s2;"),
            std::string::npos)
      << "a case without a fit is named, not dropped silently";

  // Recovery of the heuristic: |errors| 10 % and 30 % within 1 mm (median 20 %), 2 % at 4 mm.
  const std::string recovery = readText(dir / "recovery.csv");
  EXPECT_NE(recovery.find("heuristic,0–1 mm,2,20.000,"), std::string::npos) << recovery;
  EXPECT_NE(recovery.find("heuristic,3–6 mm,1,2.000,2.000"), std::string::npos) << recovery;
  EXPECT_NE(recovery.find("heuristic,all,3,10.000,"), std::string::npos) << recovery;
  EXPECT_EQ(recovery.find("truth,"), std::string::npos) << "truth recovers itself trivially";

  r = runRunner("merge --smoke --allow-missing --no-timing --results " + quoted(dir.path()));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(readText(dir / "table1.csv").find("wall_seconds"), std::string::npos);

  // A subset of the full plan without the sensitivity sweeps' base case (prolapse-P2_s1) and
  // the optimiser cases: merged and checked (it stopped with "no case prolapse-P2_s1"). The
  // full plan's normal-1_s2 is another case than the smoke plan's (edge 2.5 mm, 6 planes).
  const FixtureCase full_case{"normal-1_s2", 2.5, 6, 0.3};
  writeText(dir / "jobs" / "normal-1_s2__heuristic.json",
            fixtureResult(full_case, "heuristic", 1.25, {{0.5, 0.10}}).dump());
  writeText(dir / "jobs" / "normal-1_s2__truth.json",
            fixtureResult(full_case, "truth", 0.40, {{0.5, 0.0}}).dump());
  const std::string subset = " --presets normal-1 --seeds 2 --methods heuristic,truth ";
  r = runRunner("merge --allow-missing" + subset + "--results " + quoted(dir.path()));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(readText(dir / "sensitivity.md").find("No rows: the plan does not hold"),
            std::string::npos);
  // Without fit jobs in the subset nothing is judged, and no case is called "not judged" as if
  // its results were missing (every case of the full plan was listed).
  const std::string acceptance = readText(dir / "acceptance.md");
  EXPECT_NE(acceptance.find("**No case to judge**"), std::string::npos) << acceptance;
  EXPECT_EQ(acceptance.find("**Not judged**"), std::string::npos) << acceptance;
  r = runRunner("check" + subset + "--results " + quoted(dir.path()));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
}

// The sensitivity variants are cases of their own (prolapse-P2_s1_noise0, ..._planes3): a merge
// of a subset without them used to fill all seven rows with the base case's numbers.
TEST_F(ExperimentsPipeline, SensitivityRowsComeOnlyFromTheirOwnCases) {
  TempDir dir;
  writeSweepCase(dir.path(), {"prolapse-P2_s1", 2.5, 6, 0.3}, 0.46);
  writeSweepCase(dir.path(), {"prolapse-P2_s1_noise0", 2.5, 6, 0.0}, 0.38);
  auto r = runRunner("merge --allow-missing --no-timing --cases prolapse-P2_s1 --results " +
                     quoted(dir.path()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto rows = lines(readText(dir / "sensitivity.csv"));
  ASSERT_EQ(rows.size(), 3u) << "header, noise 0.3 and planes 6: the base case's own values\n"
                             << readText(dir / "sensitivity.csv");
  EXPECT_EQ(rows[1].rfind("noise σ,0.3,prolapse-P2_s1,2.0000,0.4600,", 0), 0u) << rows[1];
  EXPECT_EQ(rows[2].rfind("planes,6,prolapse-P2_s1,", 0), 0u) << rows[2];
  std::string md = readText(dir / "sensitivity.md");
  EXPECT_NE(md.find("**Not in the plan** (rows left out"), std::string::npos) << md;
  EXPECT_NE(md.find("noise σ 0.0 (prolapse-P2_s1_noise0)"), std::string::npos) << md;
  EXPECT_NE(md.find("planes 12 (prolapse-P2_s1_planes12)"), std::string::npos) << md;
  EXPECT_EQ(md.find("| noise σ | 0.0 |"), std::string::npos) << md;

  // With the variant selected, its row has its own fit (0.38, not the base case's 0.46); a
  // variant of the plan without results is a row marked missing.
  r = runRunner(
      "merge --allow-missing --no-timing --cases prolapse-P2_s1,prolapse-P2_s1_noise0,"
      "prolapse-P2_s1_noise0.6 --results " +
      quoted(dir.path()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  rows = lines(readText(dir / "sensitivity.csv"));
  ASSERT_EQ(rows.size(), 5u) << readText(dir / "sensitivity.csv");
  EXPECT_EQ(rows[1].rfind("noise σ,0.0,prolapse-P2_s1_noise0,2.0000,0.3800,", 0), 0u) << rows[1];
  EXPECT_EQ(rows[3], "noise σ,0.6,prolapse-P2_s1_noise0.6,,,,,,") << "no numbers of another case";
  md = readText(dir / "sensitivity.md");
  EXPECT_NE(md.find("| noise σ | 0.6 | – | – | – | – | – | – |"), std::string::npos) << md;
  EXPECT_NE(md.find("`prolapse-P2_s1_noise0.6__fit_scales_ceres`"), std::string::npos)
      << "the missing jobs are named: " << md;

  // A variant alone: its row, though the plan does not hold the base case.
  r = runRunner("merge --allow-missing --no-timing --cases prolapse-P2_s1_noise0 --results " +
                quoted(dir.path()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  rows = lines(readText(dir / "sensitivity.csv"));
  ASSERT_EQ(rows.size(), 2u) << readText(dir / "sensitivity.csv");
  EXPECT_EQ(rows[1].rfind("noise σ,0.0,prolapse-P2_s1_noise0,", 0), 0u) << rows[1];
}

// Job results record the options they were made with (max_sims, scale_bounds, edge_mm, ...):
// a run with other options used to skip them as "result present", and a merge with other
// options labelled the tables with them.
TEST_F(ExperimentsPipeline, ResultsMadeWithOtherOptionsAreRefusedNotReused) {
  TempDir dir;
  const fs::path results = dir / "results";
  writeText(results / "jobs" / "normal-1_s2__heuristic.json",
            fixtureResult("heuristic", 1.25, {{0.5, 0.1}}).dump());
  writeText(results / "jobs" / "normal-1_s2__truth.json",
            fixtureResult("truth", 0.40, {{0.5, 0.0}}).dump());
  nlohmann::json fit = fixtureResult("fit_scales_ceres", 0.30, {{0.5, 0.02}});
  fit["max_sims"] = 80;  // the smoke plan's budget
  fit["convergence"] = {{"forward_sims", {1, 2}}, {"mean_mm", {1.25, 0.30}}};
  writeText(results / "jobs" / "normal-1_s2__fit_scales_ceres.json", fit.dump());
  const std::string where = " --results " + quoted(results) + " --work " + quoted(dir / "work") +
                            " --chordfit " + quoted(dir / "no-chordfit");

  // run: refused before anything runs, naming the job, both values and the ways out.
  auto r = runRunner("run --smoke --methods fit_scales_ceres --max-sims 150" + where);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("job normal-1_s2__fit_scales_ceres has a result made with other options"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("records max_sims 80, this run asks for 150 (--max-sims)"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("--force"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("another --results"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "work")) << "nothing ran";
  r = runRunner("run --smoke --methods fit_scales_ceres --scale-bounds 0.6,1.5" + where);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("records scale_bounds the fit's default, this run asks for 0.6,1.5"),
            std::string::npos)
      << r.err;
  r = runRunner("run --smoke --methods heuristic --edge 2" + where);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("records edge_mm 3, this run asks for 2 (--edge)"), std::string::npos)
      << r.err;

  // merge: refused, nothing written; with the jobs' options it merges.
  r = runRunner("merge --smoke --allow-missing --max-sims 150" + where);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("merge: job normal-1_s2__fit_scales_ceres was run with other options"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("records max_sims 80, the merge asks for 150 (--max-sims)"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(results / "table1.csv"));
  // The smoke plan's results merged without --smoke: the edge is the smoke plan's, and the
  // message used to suggest only --edge.
  r = runRunner("merge --allow-missing --methods heuristic" + where);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("records edge_mm 3, the merge asks for 2.5 (--edge) (--plan smoke's value: "
                       "were they made with --plan smoke?)"),
            std::string::npos)
      << r.err;
  // Its own plan's value gets no such hint.
  EXPECT_EQ(runRunner("merge --smoke --allow-missing --max-sims 150" + where)
                .err.find("--plan smoke's value"),
            std::string::npos);
  r = runRunner("merge --smoke --allow-missing" + where);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string index = readText(results / "index.md");
  EXPECT_NE(index.find("Plan options: `--plan smoke`; plan id `"), std::string::npos) << index;

  // check: the same, naming the first job and field.
  r = runRunner("check --smoke --scale-bounds 0.6,1.5" + where);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("check: job normal-1_s2__fit_scales_ceres was run with other options"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("scale_bounds the fit's default, the check asks for 0.6,1.5"),
            std::string::npos)
      << r.err;

  // The plan options and id name a budget, edge or bounds other than the plan's defaults; the
  // budget and bounds only where the plan has a fit job to use them.
  const auto id = [](const std::string& text) {
    const std::size_t at = text.find("plan id `");
    return at == std::string::npos ? std::string() : text.substr(at, 26);
  };
  r = runRunner(
      "merge --smoke --allow-missing --methods heuristic,fit_scales_ceres --max-sims 80"
      " --scale-bounds 0.6,1.5" +
      where);
  EXPECT_EQ(r.exit_code, 2) << "the fit was run with the default bounds: " << r.err;
  r = runRunner("merge --smoke --allow-missing --methods heuristic,truth --max-sims 150" + where);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string budget = readText(results / "index.md");
  EXPECT_NE(budget.find("Plan options: `--plan smoke --methods heuristic,truth`;"),
            std::string::npos)
      << "no fit job uses the budget: " << budget;
  r = runRunner("merge --smoke --allow-missing --methods heuristic,truth" + where);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string plain = readText(results / "index.md");
  EXPECT_EQ(id(budget), id(plain)) << budget << plain;
  r = runRunner("check --smoke --methods heuristic,truth --max-sims 150" + where);
  EXPECT_EQ(r.exit_code, 0) << "the budget is not part of this plan: " << r.err;
  r = runRunner("check --smoke --methods heuristic" + where);
  EXPECT_EQ(r.exit_code, 1) << "merged with the truth jobs too: " << r.err;
  EXPECT_NE(r.err.find("was merged with `--plan smoke --methods heuristic,truth`, another plan "
                       "than this check's `--plan smoke --methods heuristic`"),
            std::string::npos)
      << r.err;
  r = runRunner(
      "merge --smoke --allow-missing --methods heuristic,truth,fit_scales_ceres "
      "--max-sims 80" +
      where);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string with_fit = readText(results / "index.md");
  EXPECT_NE(id(with_fit), id(plain)) << "another plan: its jobs differ";
  r = runRunner("check --smoke --methods heuristic,truth,fit_scales_ceres --max-sims 150" + where);
  EXPECT_EQ(r.exit_code, 1) << "the fit was run with a budget of 80: " << r.err;
  r = runRunner("check --smoke --methods heuristic,truth,fit_scales_ceres --edge 3 --max-sims 80" +
                where);
  EXPECT_EQ(r.exit_code, 0) << "the plan's defaults given explicitly: " << r.err;

  // A case in --work made with other options is refused even with --force (which reruns jobs,
  // it does not remake cases): its jobs would be labelled with options it was not made with.
  const fs::path bundled = fs::path(CHORDFIT_EXE).parent_path().parent_path() / "cases";
  ASSERT_TRUE(fs::exists(bundled / "small-normal" / "case.json")) << "build target cohort_cases";
  fs::create_directories(dir / "work" / "cases");
  fs::copy(bundled / "small-normal", dir / "work" / "cases" / "normal-1_s2",
           fs::copy_options::recursive);
  r = runRunner("run --smoke --methods heuristic --force --edge 2.5" + where);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("case normal-1_s2 in "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("was made with generation.case_edge_mm 3, this run asks for 2.5 (--edge)"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("another --work"), std::string::npos) << r.err;
}

TEST_F(ExperimentsPipeline, AcceptanceTableJudgesTheIssueCriteriaPerCase) {
  TempDir dir;
  writeText(dir / "jobs" / "normal-1_s2__heuristic.json",
            fixtureResult("heuristic", 1.25, {{0.5, 0.30}}).dump());
  writeText(dir / "jobs" / "normal-1_s2__truth.json",
            fixtureResult("truth", 0.40, {{0.5, 0.0}}).dump());
  // Within 3 mm: |errors| 2 % and 4 % (median 3 %: met); the cord at 5 mm does not count.
  nlohmann::json fit =
      fixtureResult("fit_scales_ceres", 0.30, {{0.5, 0.02}, {2.0, -0.04}, {5.0, 0.5}});
  // A ruptured cord near a plane has no true rest length: left out (its 900 % would count).
  fit["cords"].push_back(fit["cords"][0]);
  fit["cords"][3]["index"] = 3;
  fit["cords"][3]["ruptured"] = true;
  fit["cords"][3]["relative_error"] = 9.0;
  fit["convergence"] = {{"forward_sims", {1, 2}}, {"mean_mm", {1.25, 0.30}}};
  // In the planes: none, as traced (reconstructed); the tissue judgement says A1 (not).
  fit["metrics"]["section_prolapse_segments"] = nlohmann::json::array();
  fit["metrics"]["prolapse_reconstructed"] = true;
  fit["metrics"]["tissue_prolapse_reconstructed"] = false;
  writeText(dir / "jobs" / "normal-1_s2__fit_scales_ceres.json", fit.dump());
  const auto r =
      runRunner("merge --smoke --allow-missing --no-timing --results " + quoted(dir.path()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = lines(readText(dir / "acceptance.csv"));
  ASSERT_EQ(rows.size(), 2u) << readText(dir / "acceptance.csv");
  // Taut in the truth: cords 0 and 2, of which only cord 0 lies within 3 mm (2 %).
  EXPECT_EQ(rows[1],
            "normal-1_s2,normal-1,no,1.2500,0.3000,76.0,0.4000,0.750,0.4000,,,yes,A1,no,,yes,4,1,2,"
            "3.00,1,2.00,1,");  // no tissue_retry: a result from before the retry
  const std::string md = readText(dir / "acceptance.md");
  // A normal preset: the planes must show no prolapse, as they do.
  EXPECT_NE(md.find("| none / none ✓ | A1 ✗ | none ✓ | 3.0 % (2 of 4, 1 ruptured) ✓ | 2.0 % (1) "
                    "✓ |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("`chordfit make-case --edge 3.00 --planes 3"), std::string::npos) << md;
  // normal-1 is not pathological: the reduction criterion does not apply to it.
  EXPECT_NE(
      md.find("AvgD reduction 0 of 0 cases; within 1.5× the noise floor 1 of 1 cases; "
              "prolapse reconstructed 1 of 1 cases (tissue judgement: 0 of 1 cases); prolapse in "
              "the preset's segments 1 of 1 cases; recovery 1 of 1 cases (cords taut in the truth: "
              "1 of 1 cases). Cords within 3 mm of a plane: 2 of 3 unruptured (1 ruptured left "
              "out)."),
      std::string::npos)
      << md;

  // A fit that kept its tissue retry: named after the verdict, "yes" in the CSV.
  fit["tissue_retry"] = {{"ran", true}, {"kept", true}, {"tissue", {"P3 0.3, cords 1.5"}}};
  writeText(dir / "jobs" / "normal-1_s2__fit_scales_ceres.json", fit.dump());
  ASSERT_EQ(runRunner("merge --smoke --allow-missing --no-timing --results " + quoted(dir.path()))
                .exit_code,
            0);
  EXPECT_EQ(lines(readText(dir / "acceptance.csv"))[1].substr(rows[1].size()), "yes");
  EXPECT_NE(readText(dir / "acceptance.md")
                .find("| none / none ✓ (tissue retry: P3 0.3, cords 1.5) | A1 ✗ |"),
            std::string::npos)
      << readText(dir / "acceptance.md");
}

// Real closures (chordfit make-case and simulate on the smoke case; a few seconds): results
// are the same in one piece and in two shards, and the truth closure fits its own tracings
// better than the heuristic.
TEST_F(ExperimentsPipeline, ShardedRunGivesTheSameTablesAsOneRun) {
  TempDir dir;
  // The smoke case is the bundled small-normal: copied, not generated (--case-source).
  const fs::path bundled = fs::path(CHORDFIT_EXE).parent_path().parent_path() / "cases";
  ASSERT_TRUE(fs::exists(bundled / "small-normal" / "case.json")) << "build target cohort_cases";
  const std::string common = " --smoke --methods heuristic,truth --case-source " + quoted(bundled) +
                             " --work " + quoted(dir / "work");
  auto r = runRunner("all" + common + " --results " + quoted(dir / "whole"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The start of a run names, in full, the directories and the chordfit it uses.
  EXPECT_NE(r.err.find("run_experiments: results in " + (dir / "whole").string() + ", work in " +
                       (dir / "work").string() + ", chordfit " + CHORDFIT_EXE + " (revision "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("[job 1/2] normal-1_s2__heuristic: AvgD"), std::string::npos) << r.err;
  for (int i = 1; i <= 2; ++i) {
    r = runRunner("run" + common + " --shard " + std::to_string(i) + "/2 --results " +
                  quoted(dir / "sharded"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  for (const char* results : {"whole", "sharded"}) {
    r = runRunner("merge" + common + " --no-timing --results " + quoted(dir / results));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  for (const char* file : {"table1.csv", "table1.md", "recovery.csv", "recovery_cords.csv",
                           "sensitivity.csv", "sensitivity.svg"}) {
    EXPECT_EQ(readText(dir / "whole" / file), readText(dir / "sharded" / file)) << file;
  }
  const auto table = lines(readText(dir / "whole" / "table1.csv"));
  ASSERT_EQ(table.size(), 4u);
  const double heuristic = std::stod(cells(table[1])[9]);
  const double truth = std::stod(cells(table[2])[9]);
  const double floor = std::stod(cells(table[3])[9]);
  EXPECT_LT(truth, heuristic);
  EXPECT_LT(floor, heuristic);
  // Every job records where it ran (wall times compare only within one machine).
  const auto job =
      nlohmann::json::parse(readText(dir / "whole" / "jobs" / "normal-1_s2__truth.json"));
  ASSERT_TRUE(job.contains("machine"));
  EXPECT_NE(job.at("machine").get<std::string>().find("logical CPUs"), std::string::npos);
  const std::string index = readText(dir / "whole" / "index.md");
  // ... and how many jobs ran there (here both: the heuristic and the truth).
  EXPECT_NE(index.find("Machine(s) the jobs ran on: `" + job.at("machine").get<std::string>() +
                       "` (2 jobs)"),
            std::string::npos)
      << index;
}

// A stand-in for chordfit (run_experiments --chordfit): answers --version, appends each other
// command's name to dir/calls and its pid to dir/child.pid, then runs `then` ("exec sleep 60":
// the same pid, sleeping; "exit 130": chordfit's exit after Ctrl-C).
fs::path writeFakeChordfit(const fs::path& dir, const std::string& then) {
  const fs::path fake = dir / "chordfit";
  writeText(fake,
            "#!/bin/sh\ncase \"$1\" in --version) echo 'chordfit 0.1.0 (revision fake)'; "
            "exit 0;; esac\necho \"$1\" >> " +
                quoted(dir / "calls") + "\necho $$ > " + quoted(dir / "child.pid") + "\n" + then +
                "\n");
  fs::permissions(fake, fs::perms::owner_all);
  return fake;
}

// Starts the runner in the background (stderr to `err`), in a process group of its own when
// `own_group` (as a shell with job control starts a command, so that Ctrl-C reaches the group).
pid_t startRunner(const std::string& arguments, const fs::path& err, bool own_group) {
  const std::string command =
      "exec " + quoted(runnerPath()) + " " + arguments + " >/dev/null 2>" + quoted(err);
  const pid_t pid = fork();
  if (pid == 0) {
    if (own_group) setpgid(0, 0);
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  if (own_group && pid > 0) setpgid(pid, pid);  // either side may win the race; both set it
  return pid;
}

// The pid the fake chordfit recorded, waiting up to 30 s for it; 0 when it never started.
pid_t waitForFakeChild(const fs::path& dir) {
  for (int k = 0; k < 300; ++k) {
    if (fs::exists(dir / "child.pid")) {
      const std::string text = readText(dir / "child.pid");
      if (!text.empty() && text.back() == '\n') return static_cast<pid_t>(std::stol(text));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return 0;
}

// The runner's wait status, waiting up to 30 s (then killed: -1).
int waitForRunner(pid_t pid) {
  int status = 0;
  for (int k = 0; k < 300; ++k) {
    if (waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return -1;
}

// Whether `pid` is still running; kills it when it is (an orphan the test must not leave).
bool stillRunning(pid_t pid) {
  if (pid <= 0 || kill(pid, 0) != 0) return false;
  kill(pid, SIGKILL);
  return true;
}

// Ctrl-C or a kill stops the whole run (SIGINT to the process group used to kill only the
// running chordfit, and run_experiments logged "FAILED ... exit code 130" and started the next
// job; SIGTERM to run_experiments alone left its chordfit running as an orphan).
TEST_F(ExperimentsPipeline, ASignalStopsTheWholeRunAndLeavesNoChildOrHalfResult) {
  const fs::path bundled = fs::path(CHORDFIT_EXE).parent_path().parent_path() / "cases";
  ASSERT_TRUE(fs::exists(bundled / "small-normal" / "case.json")) << "build target cohort_cases";
  auto options = [&](const TempDir& dir, const fs::path& fake) {
    return " --smoke --methods heuristic,truth --case-source " + quoted(bundled) + " --chordfit " +
           quoted(fake) + " --work " + quoted(dir / "work") + " --results " +
           quoted(dir / "results");
  };
  auto calls = [](const TempDir& dir) { return lines(readText(dir / "calls")).size(); };
  {  // The job's chordfit died of Ctrl-C (exit 130): the run stops, the next job never starts.
    TempDir dir;
    const fs::path fake = writeFakeChordfit(dir.path(), "exit 130");
    const auto r = runRunner("run" + options(dir, fake));
    EXPECT_EQ(r.exit_code, 130) << r.err;
    EXPECT_EQ(calls(dir), 1u) << "the truth job did not start: " << r.err;
    EXPECT_NE(r.err.find("stopped by SIGINT during job 1/2 (normal-1_s2__heuristic)"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find("FAILED"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("run_experiments: resume with: "), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "results" / "jobs" / "normal-1_s2__heuristic.json"));
  }
  {  // A case that failed to generate is counted apart from the jobs when a stop ends the run
     // (it was counted as a failed job: "1 failed, 1 of the shard's 2 not done").
    TempDir dir;
    const fs::path fake = writeFakeChordfit(
        dir.path(), "[ \"$(wc -l < " + quoted(dir / "calls") + ")\" -eq 1 ] && exit 1\nexit 130");
    const auto r =
        runRunner("run --smoke --methods heuristic,truth --chordfit " + quoted(fake) + " --work " +
                  quoted(dir / "work") + " --results " + quoted(dir / "results"));
    EXPECT_EQ(r.exit_code, 130) << r.err;
    EXPECT_NE(r.err.find("[case 1/1] FAILED"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("0 failed, 2 of the shard's 2 not done"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("and 1 case(s) failed to generate"), std::string::npos) << r.err;
  }
  // kill -TERM run_experiments: forwarded to its chordfit, waited for, exit 143. SIGHUP (the
  // terminal of a shard closed) the same, forwarded as SIGTERM, exit 129: it killed
  // run_experiments alone and left its chordfit running as an orphan; then it was reported as
  // SIGTERM.
  for (const int signal_number : {SIGTERM, SIGHUP}) {
    const std::string name = signal_number == SIGTERM ? "SIGTERM" : "SIGHUP";
    SCOPED_TRACE(name);
    TempDir dir;
    const fs::path fake = writeFakeChordfit(dir.path(), "exec sleep 60");
    const pid_t runner = startRunner("run --force" + options(dir, fake), dir / "err", false);
    ASSERT_GT(runner, 0);
    const pid_t child = waitForFakeChild(dir.path());
    ASSERT_GT(child, 0) << readText(dir / "err");
    kill(runner, signal_number);
    const int status = waitForRunner(runner);
    const std::string err = readText(dir / "err");
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 128 + signal_number)
        << "status " << status << err;
    EXPECT_FALSE(stillRunning(child)) << "the chordfit of the job was left running";
    EXPECT_EQ(calls(dir), 1u) << err;
    EXPECT_NE(err.find("stopped by " + name + " during job 1/2 (normal-1_s2__heuristic)"),
              std::string::npos)
        << err;
    EXPECT_NE(err.find("this run finished 0 job(s) with a result"), std::string::npos) << err;
    EXPECT_NE(err.find("resume with: "), std::string::npos) << err;
    // A --force run keeps --force in its resume: the jobs it did not reach still hold results
    // from before it, which a plain resume would keep beside the new ones.
    EXPECT_NE(err.find("--force", err.find("resume with: ")), std::string::npos) << err;
    EXPECT_NE(err.find("(--force kept: the jobs this run did not reach still hold results"),
              std::string::npos)
        << err;
    EXPECT_FALSE(fs::exists(dir / "results" / "jobs" / "normal-1_s2__heuristic.json"));
  }
  {  // A chordfit deaf to the forwarded stop is killed after a grace period: the run still ends.
    TempDir dir;
    const fs::path fake = writeFakeChordfit(
        dir.path(), "trap '' TERM INT\n: > " + quoted(dir / "deaf") + "\nexec sleep 60");
    const pid_t runner = startRunner("run --force" + options(dir, fake), dir / "err", false);
    ASSERT_GT(runner, 0);
    const pid_t child = waitForFakeChild(dir.path());
    ASSERT_GT(child, 0) << readText(dir / "err");
    for (int k = 0; k < 100 && !fs::exists(dir / "deaf"); ++k)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    ASSERT_TRUE(fs::exists(dir / "deaf")) << "the fake never set its trap";
    kill(runner, SIGTERM);
    const int status = waitForRunner(runner);
    const std::string err = readText(dir / "err");
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 143) << "status " << status << err;
    EXPECT_FALSE(stillRunning(child)) << "the chordfit of the job was left running";
    EXPECT_NE(err.find("did not end within 5 s of the stop signal: killed (SIGKILL)"),
              std::string::npos)
        << err;
    EXPECT_EQ(calls(dir), 1u) << err;
  }
  {  // Ctrl-C: SIGINT to the whole process group during `all`: exit 130, no merge.
    TempDir dir;
    const fs::path fake = writeFakeChordfit(dir.path(), "exec sleep 60");
    const pid_t runner = startRunner("all" + options(dir, fake), dir / "err", true);
    ASSERT_GT(runner, 0);
    const pid_t child = waitForFakeChild(dir.path());
    ASSERT_GT(child, 0) << readText(dir / "err");
    kill(-runner, SIGINT);
    const int status = waitForRunner(runner);
    const std::string err = readText(dir / "err");
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 130) << "status " << status << err;
    EXPECT_FALSE(stillRunning(child));
    EXPECT_EQ(calls(dir), 1u) << err;
    EXPECT_NE(err.find("stopped by SIGINT during job 1/2"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "results" / "table1.csv")) << "a stopped `all` does not merge";
  }
}

// A job result that cannot be one (truncated, another job's file, or replaced by a failed
// rerun) is never tabulated: `run` runs such a job again, a rerun removes the old result before
// it starts (a failed --force rerun used to leave the old one, and merge and check passed), and
// `merge` refuses a bad file by name before it writes any table.
TEST_F(ExperimentsPipeline, BadOrStaleJobResultsAreRunAgainOrRefusedByName) {
  TempDir dir;
  const fs::path jobs = dir / "results" / "jobs";
  const fs::path heuristic = jobs / "normal-1_s2__heuristic.json";
  const fs::path truth = jobs / "normal-1_s2__truth.json";
  const std::string good_heuristic = fixtureResult("heuristic", 1.25, {{0.5, 0.10}}).dump();
  const std::string good_truth = fixtureResult("truth", 0.40, {{0.5, 0.0}}).dump();
  writeText(heuristic, good_heuristic);
  writeText(truth, good_truth);
  const std::string merge =
      "merge --smoke --methods heuristic,truth --no-timing --results " + quoted(dir / "results");
  ASSERT_EQ(runRunner(merge).exit_code, 0);
  const std::string table = readText(dir / "results" / "table1.csv");

  // merge: a truncated file and a file of another job are named; no table is written.
  writeText(heuristic, good_heuristic.substr(0, good_heuristic.size() / 2));
  auto r = runRunner(merge);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(heuristic.string() + ": is not a JSON object (truncated or edited?)"),
            std::string::npos)
      << r.err;
  writeText(heuristic, good_truth);
  r = runRunner(merge);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(heuristic.string() +
                       ": is the result of job normal-1_s2__truth (a file copied under another "
                       "name?)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(readText(dir / "results" / "table1.csv"), table) << "tables rewritten";

  // run: the bad result is run again (here by a chordfit that fails, so no result is left).
  const fs::path bundled = fs::path(CHORDFIT_EXE).parent_path().parent_path() / "cases";
  const fs::path fake = writeFakeChordfit(dir.path(), "exit 1");
  const std::string run = "run --smoke --methods heuristic,truth --case-source " + quoted(bundled) +
                          " --chordfit " + quoted(fake) + " --work " + quoted(dir / "work") +
                          " --results " + quoted(dir / "results");
  r = runRunner(run);
  EXPECT_EQ(lines(readText(dir / "calls")).size(), 1u) << "only the bad result's job: " << r.err;
  EXPECT_FALSE(fs::exists(heuristic)) << r.err;
  EXPECT_TRUE(fs::exists(truth));
  // run --force with a chordfit that fails: the old result does not outlive the failed rerun.
  r = runRunner(run + " --force");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_FALSE(fs::exists(truth)) << r.err;
  r = runRunner("check --smoke --methods heuristic,truth --results " + quoted(dir / "results"));
  EXPECT_NE(r.exit_code, 0) << "the tables are of results that are gone: " << r.err;

  // No chordfit: refused before the first case (every case and job failed in turn).
  r = runRunner("run --smoke --methods heuristic --chordfit " + quoted(dir / "none" / "chordfit") +
                " --work " + quoted(dir / "work") + " --results " + quoted(dir / "results"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/none/chordfit: no such file"), std::string::npos) << r.err;
  // A case directory without a case.json is named as such ("missing after generation").
  const fs::path other_work = dir / "other-work";
  writeText(other_work / "cases" / "normal-1_s2" / "cords.json", "{}");
  r = runRunner("run --smoke --methods heuristic --case-source " + quoted(bundled) +
                " --chordfit " + quoted(fake) + " --work " + quoted(other_work) + " --results " +
                quoted(dir / "results"));
  EXPECT_NE(r.err.find("normal-1_s2 is there without a case.json (left half-made?): remove it"),
            std::string::npos)
      << r.err;
}

// calibrate_cohort (experiments/README.md "Calibration"): one preset and seed at a coarse edge,
// with a changed preset value; bad keys, presets and values exit 2 naming the problem.
TEST(CalibrateCohort, PrintsTheSegmentHeightsAndRejectsBadSettings) {
  const fs::path tool = runnerPath().parent_path() / "calibrate_cohort";
  auto r =
      testing::runProgram(tool, "normal-1 --seeds 1 --edge 3 --max-steps 1500 --ramp 8 normal=0.8");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = lines(r.out);
  ASSERT_EQ(rows.size(), 3u) << r.out;
  EXPECT_EQ(rows[0].rfind("| Seed | Mesh prolapse | Tracing prolapse | A1 |", 0), 0u) << rows[0];
  EXPECT_EQ(rows[2].rfind("| 1 | – | ", 0), 0u) << "normal-1 seed 1 does not prolapse: " << rows[2];
  expectUsageErrors(tool,
                    {{"normal-1 foo=1", "unknown key \"foo\""},
                     {"normal-1 lesion=soft", "lesion: expected a number"},
                     {"normal-1 lesion_segments=A4", "\"A4\" is not A1..P3"},
                     {"normal-3", "unknown preset \"normal-3\""},
                     {"normal-1 --edge 0", "--edge: expected a positive length"},
                     {"normal-1 --seeds 1,1.5", "--seeds: expected positive integers, got \"1.5\""},
                     {"normal-1 --max-steps 0", "--max-steps: expected a positive integer"},
                     {"normal-1 --ramp -1", "--ramp: expected a positive duration"},
                     {"normal-1 --ramp", "--ramp: expected a positive duration"}});
}

// mesh_convergence (docs/performance.md "Mesh convergence of the closed valve"): the
// reference lies on its own noise-free tracings, a coarser mesh of the same valve does not
// quite; bad arguments exit 2 naming the problem.
TEST(MeshConvergence, MeasuresACoarserMeshAgainstTheReferenceAndRejectsBadArguments) {
  const fs::path tool = runnerPath().parent_path() / "mesh_convergence";
  auto r = testing::runProgram(tool, "normal-1 --seeds 1 --reference 1.5 --edges 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = lines(r.out);
  ASSERT_EQ(rows.size(), 4u) << r.out;
  EXPECT_EQ(rows[0].rfind("| Seed | Edge (mm) | Vertices |", 0), 0u) << rows[0];
  const auto reference = markdownCells(rows[2]), coarse = markdownCells(rows[3]);
  ASSERT_GE(reference.size(), 7u) << rows[2];
  ASSERT_GE(coarse.size(), 7u) << rows[3];
  EXPECT_DOUBLE_EQ(std::stod(reference[2]), 1.5);
  EXPECT_LT(std::stod(reference[5]), 1e-3) << "the reference lies on its tracings";
  EXPECT_DOUBLE_EQ(std::stod(coarse[2]), 3.0);
  EXPECT_LT(std::stoi(coarse[3]), std::stoi(reference[3])) << "fewer vertices";
  EXPECT_GT(std::stod(coarse[5]), 0.01) << "a coarser mesh closes a little differently";
  EXPECT_LT(std::stod(coarse[5]), 1.0) << "but it is the same valve";
  expectUsageErrors(
      tool, {{"normal-3", "unknown preset \"normal-3\""},
             {"normal-1 --edges 3,x", "--edges: expected positive lengths in mm, got \"x\""},
             {"normal-1 --edges 0.5", "0.5 mm is not coarser than the reference (0.6 mm)"},
             {"normal-1 --reference -1", "--reference: expected a positive length"},
             {"normal-1 --seeds 0", "--seeds: expected positive integers, got \"0\""},
             {"normal-1 --foo", "unknown argument \"--foo\""}});
}

// coarse_start (docs/performance.md, "Coarse-to-fine start"): the same valve closed cold and
// warm-started from a coarser mesh's closure; on normal-1 seed 2 at edge 1.5 mm both land on
// the same closed state. Bad arguments exit 2 naming the problem.
TEST(CoarseStart, ClosesTheValveBothWaysAndRejectsBadArguments) {
  const fs::path tool = runnerPath().parent_path() / "coarse_start";
  auto r = testing::runProgram(tool, "normal-1 --seeds 2 --edge 1.5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = lines(r.out);
  ASSERT_EQ(rows.size(), 3u) << r.out;
  EXPECT_EQ(rows[0].rfind("| Seed | Vertices fine / coarse |", 0), 0u) << rows[0];
  const auto cells = markdownCells(rows[2]);
  ASSERT_GE(cells.size(), 11u) << rows[2];
  const int fine = std::stoi(cells[2]);
  const int coarse = std::stoi(cells[2].substr(cells[2].find('/') + 1));
  EXPECT_LT(coarse, fine / 2) << "the coarse mesh has about a quarter of the vertices";
  for (int column : {3, 4, 6})
    EXPECT_EQ(cells[column].find("cap"), std::string::npos) << "every closure settles: " << rows[2];
  const double apart_max = std::stod(cells[8].substr(cells[8].find('/') + 1));
  EXPECT_LT(apart_max, 0.05) << "both starts reach the same closed state here: " << rows[2];
  expectUsageErrors(tool, {{"normal-3", "unknown preset \"normal-3\""},
                           {"normal-1 --ratio 1", "--ratio: expected a number in (1, 4]"},
                           {"normal-1 --edge 0.1", "--edge: expected a length in [0.3, 5] mm"},
                           {"normal-1 --seeds x", "--seeds: expected positive integers"},
                           {"normal-1 --foo", "unknown argument \"--foo\""}});
}

}  // namespace
}  // namespace chordfit
