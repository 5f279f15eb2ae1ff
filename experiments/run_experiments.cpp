// run_experiments: the benchmark experiments of issue "Benchmark experiments" in one command.
// Generates the cohort cases, runs every (case x method) job through the chordfit program and
// merges the per-job results into the tables and plots of experiments/results/. See
// experiments/README.md, "Benchmark experiments". Arguments are parsed by hand (CLI11 is
// confined to tools/main.cpp for build time).
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/csv_text.h"
#include "core/joined.h"
#include "core/synthetic_case.h"
#include "experiments/acceptance_table.h"
#include "experiments/experiment_jobs.h"
#include "experiments/experiment_plan.h"
#include "experiments/experiment_tables.h"
#include "experiments/result_fields.h"

namespace {

namespace fs = std::filesystem;
using namespace chordfit::experiments;
using chordfit::joined;
using Clock = std::chrono::steady_clock;

constexpr int kExitOk = 0;
constexpr int kExitJobsFailed = 1;
constexpr int kExitUsage = 2;
// A run stopped by a signal exits 128 + the signal, as a shell reports a process it killed.
constexpr int kExitSignalBase = 128;
// Jobs named one by one in merge's and check's messages; beyond, a count (index.md lists all).
constexpr std::size_t kListedAtMost = 10;

// The default directories: deliberately those of the source tree this program was built from
// (its committed experiments/results), whatever the working directory, and for --plan smoke the
// build tree's. A copied binary run elsewhere still writes there, so --help and the start of a
// run print them in full.
fs::path defaultBase(bool smoke) {
  return smoke ? fs::path(CHORDFIT_BINARY_DIR) / "experiments" / "smoke"
               : fs::path(CHORDFIT_SOURCE_DIR) / "experiments";
}

// kUsage with its @RESULTS@, @WORK@, @SMOKE_RESULTS@, @SMOKE_WORK@ and @CHORDFIT@ replaced.
std::string usageText(std::string text) {
  const std::pair<const char*, std::string> paths[] = {
      {"@SMOKE_RESULTS@", (defaultBase(true) / "results").string()},
      {"@SMOKE_WORK@", (defaultBase(true) / "work").string()},
      {"@RESULTS@", (defaultBase(false) / "results").string()},
      {"@WORK@", (defaultBase(false) / "work").string()},
      {"@CHORDFIT@", CHORDFIT_EXE}};
  for (const auto& [key, value] : paths) {
    for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at))
      text.replace(at, std::strlen(key), value);
  }
  return text;
}

const char* kUsage = R"(usage: run_experiments COMMAND [options]

commands:
  all      run every case and job, then merge: the one command that regenerates
           experiments/results/ (from scratch after `rm -rf experiments/work
           experiments/results`, or with --force; else jobs with a result are kept)
  run      run the cases and jobs of one shard (--shard i/N); results go to RESULTS/jobs/
  merge    build the tables and plots from RESULTS/jobs/*.json (after all shards ran)
  check    verify that merged tables have every planned row and well-formed columns
  list     print the plan: its cases and jobs (under --shard i/N only that shard's)

options:
  --plan NAME        full (the default and the committed results: every preset, seeds
                     1-3, 161 jobs; about 21 min on 2 cores as two shards), reduced
                     (seed 1, optimisers on prolapse-P2 only: 61 jobs) or smoke (CI: one case,
                     one seed, small budget; default directories under the build tree,
                     BUILD/experiments/smoke/)
  --smoke            the same as --plan smoke
  --shard i/N        run only items i, i+N, i+2N, ... of the plan (1 <= i <= N)
  --results DIR      tables, plots, jobs/*.json; default, whatever the working directory,
                     the source tree this program was built from:
                       @RESULTS@
                     (--plan smoke: @SMOKE_RESULTS@)
  --work DIR         cases and run directories; default
                       @WORK@
                     (--plan smoke: @SMOKE_WORK@)
  --chordfit PATH    chordfit executable; default, the one built with this program:
                       @CHORDFIT@
  --case-source DIR  copy a case from DIR/* when its truth.json has the same generation
                     options (e.g. the bundled build/cases) instead of generating it; a case
                     without a match there is generated (its progress line says which). DIR
                     must exist
  --edge MM          case mesh edge length in [1, 5] (default 2.5; the truth mesh is half
                     of it). Case ids do not name the edge: use separate --work and --results
  --max-sims N       forward-simulation budget of every fit (full, reduced: 300; smoke: 80)
  --scale-bounds LO,HI  scale bounds of every fit (fit --scale-bounds; default the fit's
                     [0.7, 1.5]); use separate --work and --results
  --methods LIST     only jobs of these methods (comma-separated, exact names: heuristic,
                     truth, fit_groups_ceres, fit_scales_ceres, fit_scales-tips_ceres,
                     fit_scales-tissue_ceres, fit_scales_bobyqa, ...; a Ceres fit also
                     without its optimiser: fit_scales is fit_scales_ceres). NAME* selects
                     every method starting with NAME (fit*, fit_scales_*). The methods chosen
                     are printed
  --seeds LIST       only the cases of these patient seeds (comma-separated, e.g. 1)
  --presets LIST     only the cases of these presets (comma-separated)
  --cases LIST       only these cases (comma-separated ids, e.g. prolapse-P2_s1)
                     (a name of these four lists that is not in the plan is an error; merge
                     and check take the same lists and tabulate or check that subset)
  --force            rerun jobs whose result exists
  --no-timing        merge: leave out wall-time columns (to diff two runs)
  --allow-missing    merge/all: exit 0 even when some jobs have no result

Ctrl-C (SIGINT), SIGTERM or SIGHUP stops the whole run: the running chordfit gets the signal
(SIGTERM for SIGHUP) and is waited for (killed if still running 5 s later), nothing half-made is
kept, and the exit code is 130 / 143 / 129; rerun the same command (without --force) to resume.
)";

struct Arguments {
  std::string command;
  bool smoke = false;
  std::string plan = "full";
  Shard shard;
  fs::path results, work, chordfit, case_source;
  int max_sims = -1;
  double edge_mm = -1.0;
  std::optional<std::pair<double, double>> scale_bounds;
  std::vector<std::string> methods;  // empty: all
  std::vector<int> seeds;            // empty: all
  std::vector<std::string> presets;  // empty: all
  std::vector<std::string> cases;    // empty: all
  bool force = false;
  bool no_timing = false;
  bool allow_missing = false;
  // --edge, --max-sims, --scale-bounds where they differ from the plan's defaults
  // (nonDefaultOptions): part of the plan options and plan id index.md records.
  std::string option_values;
  std::vector<std::string> command_line;  // argv as given, for the resume line of a stopped run
};

int usageError(const std::string& message) {
  std::cerr << "run_experiments: error: " << message << "\n(run_experiments --help for usage)\n";
  return kExitUsage;
}

// Returns kExitOk, or the exit code to stop with.
int parseArguments(int argc, char** argv, Arguments& a) {
  std::vector<std::string> args(argv + 1, argv + argc);
  a.command_line.assign(argv, argv + argc);
  std::set<std::string> seen;  // options given so far
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    auto value = [&](std::string& out) {
      if (i + 1 >= args.size()) return false;
      out = args[++i];
      return true;
    };
    // An option given twice used to take its last value without a word (--edge 2 --edge 3,
    // --smoke --plan full); --smoke is --plan smoke.
    // --smoke beside --plan smoke says the same thing twice and is accepted.
    if (arg.rfind("--", 0) == 0) {
      const bool smoke_again = (arg == "--smoke" && seen.count("--plan") && a.plan == "smoke") ||
                               (arg == "--plan" && seen.count("--smoke") && i + 1 < args.size() &&
                                args[i + 1] == "smoke");
      if (arg == "--smoke" || arg == "--plan") {
        if (!seen.insert(arg).second) return usageError(arg + " is given twice");
        if (!smoke_again && seen.count("--smoke") && seen.count("--plan"))
          return usageError("--smoke is --plan smoke; the plan is given twice (--plan, --smoke)");
      } else if (!seen.insert(arg).second) {
        return usageError(arg + " is given twice");
      }
    }
    std::string text;
    if (arg == "--help" || arg == "-h") {
      std::cout << usageText(kUsage);
      std::exit(kExitOk);
    } else if (arg == "--smoke") {
      a.smoke = true;
      a.plan = "smoke";
    } else if (arg == "--plan") {
      if (!value(text) || (text != "full" && text != "reduced" && text != "smoke")) {
        return usageError("--plan: expected full, reduced or smoke, got \"" + text + "\"");
      }
      a.plan = text;
      a.smoke = text == "smoke";
    } else if (arg == "--force") {
      a.force = true;
    } else if (arg == "--no-timing") {
      a.no_timing = true;
    } else if (arg == "--allow-missing") {
      a.allow_missing = true;
    } else if (arg == "--shard") {
      if (!value(text) || !parseShard(text, a.shard)) {
        return usageError("--shard: expected i/N with 1 <= i <= N, got \"" + text + "\"");
      }
    } else if (arg == "--results" || arg == "--work" || arg == "--chordfit" ||
               arg == "--case-source") {
      if (!value(text) || text.empty()) return usageError(arg + ": expected a path");
      (arg == "--results"    ? a.results
       : arg == "--work"     ? a.work
       : arg == "--chordfit" ? a.chordfit
                             : a.case_source) = text;
    } else if (arg == "--methods" || arg == "--cases" || arg == "--presets") {
      if (!value(text) || text.empty()) return usageError(arg + ": expected a list");
      std::vector<std::string>& list = arg == "--methods" ? a.methods
                                       : arg == "--cases" ? a.cases
                                                          : a.presets;
      std::istringstream in(text);
      for (std::string item; std::getline(in, item, ',');) list.push_back(item);
    } else if (arg == "--seeds") {
      if (!value(text) || text.empty()) return usageError("--seeds: expected a list");
      std::istringstream in(text);
      for (std::string seed; std::getline(in, seed, ',');) {
        char* end = nullptr;
        a.seeds.push_back(static_cast<int>(std::strtol(seed.c_str(), &end, 10)));
        if (seed.empty() || *end != '\0') return usageError("--seeds: bad seed \"" + seed + "\"");
      }
    } else if (arg == "--edge") {
      char* end = nullptr;
      if (!value(text) || (a.edge_mm = std::strtod(text.c_str(), &end), *end != '\0') ||
          !(a.edge_mm >= chordfit::kMinCaseEdgeMm && a.edge_mm <= chordfit::kMaxCaseEdgeMm)) {
        char range[64];
        std::snprintf(range, sizeof range, "[%g, %g]", chordfit::kMinCaseEdgeMm,
                      chordfit::kMaxCaseEdgeMm);
        return usageError("--edge: expected a length in " + std::string(range) +
                          " mm (make-case's range), got \"" + text + "\"");
      }
    } else if (arg == "--max-sims") {
      char* end = nullptr;
      if (!value(text) || (a.max_sims = std::strtol(text.c_str(), &end, 10), *end != '\0') ||
          a.max_sims < 1) {
        return usageError("--max-sims: expected a positive integer, got \"" + text + "\"");
      }
    } else if (arg == "--scale-bounds") {
      double lo = 0.0, hi = 0.0;
      char comma = 0, trailing = 0;
      if (!value(text) ||
          std::sscanf(text.c_str(), "%lf%c%lf%c", &lo, &comma, &hi, &trailing) != 3 ||
          comma != ',' || !(lo > 0.0) || !(hi > lo)) {
        return usageError("--scale-bounds: expected LO,HI with 0 < LO < HI, got \"" + text + "\"");
      }
      a.scale_bounds = std::make_pair(lo, hi);
    } else if (!arg.empty() && arg[0] != '-' && a.command.empty()) {
      a.command = arg;
    } else {
      return usageError("unknown argument \"" + arg + "\"");
    }
  }
  if (a.command != "all" && a.command != "run" && a.command != "merge" && a.command != "check" &&
      a.command != "list") {
    return usageError(a.command.empty() ? "no command" : "unknown command \"" + a.command + "\"");
  }
  if (a.shard.count > 1 && a.command != "run" && a.command != "list") {
    return usageError("--shard applies to run and list; merge reads every shard's results");
  }
  // Switches of another command were ignored without a word (merge --force). The path
  // options are not: one set of options serves every command of a run.
  const auto ignored = [&](bool given, const char* option, const char* applies_to) {
    if (given)
      std::fprintf(stderr, "run_experiments: note: %s applies to %s; %s ignores it\n", option,
                   applies_to, a.command.c_str());
  };
  ignored(a.force && a.command != "run" && a.command != "all", "--force", "run and all");
  ignored(a.no_timing && a.command != "merge" && a.command != "all", "--no-timing",
          "merge and all");
  ignored(a.allow_missing && a.command != "merge" && a.command != "all", "--allow-missing",
          "merge and all");
  // A mistyped --case-source used to be ignored without a word (every case generated).
  if (std::error_code ec; !a.case_source.empty() && !fs::is_directory(a.case_source, ec)) {
    return usageError("--case-source " + a.case_source.string() + ": " +
                      (fs::exists(a.case_source, ec) ? "not a directory" : "no such directory") +
                      " (the directory of generated cases to copy, e.g. build/cases)");
  }
  const fs::path base = defaultBase(a.smoke);
  if (a.results.empty()) a.results = base / "results";
  if (a.work.empty()) a.work = base / "work";
  if (a.chordfit.empty()) a.chordfit = CHORDFIT_EXE;
  return kExitOk;
}

// The revision the chordfit that runs the jobs was built from, as its `--version` says
// ("chordfit 0.1.0 (revision 433c786)"); "unknown" when it does not say. (The source tree's
// revision at run time is not it: a copied binary, or a tree committed to since the build.)
std::string chordfitRevision(const fs::path& chordfit) {
  const std::string command = "'" + chordfit.string() + "' --version 2>/dev/null";
  std::string text;
  if (FILE* pipe = popen(command.c_str(), "r")) {
    char buffer[256];
    while (fgets(buffer, sizeof buffer, pipe)) text += buffer;
    pclose(pipe);
  }
  const std::string key = "(revision ";
  const std::size_t at = text.find(key);
  const std::size_t end = at == std::string::npos ? at : text.find(')', at);
  if (end == std::string::npos) return "unknown";
  return text.substr(at + key.size(), end - at - key.size());
}

// The machine the jobs run on, for reading their wall times: the CPU model of /proc/cpuinfo
// (Linux; "unknown CPU" elsewhere) and the number of logical CPUs.
std::string machineDescription() {
  std::string model;
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; model.empty() && std::getline(cpuinfo, line);) {
    const auto colon = line.find(':');
    if (line.rfind("model name", 0) == 0 && colon != std::string::npos) {
      model = line.substr(colon + 1);
      model.erase(0, model.find_first_not_of(" \t"));
    }
  }
  return (model.empty() ? std::string("unknown CPU") : model) + ", " +
         std::to_string(std::thread::hardware_concurrency()) + " logical CPUs";
}

// Whether --methods' `name` selects the method `tag`: the tag itself; a Ceres fit's tag without
// its optimiser ("fit_scales" for "fit_scales_ceres", the Table 1 fits' short names the
// documented commands use); "NAME*" every tag starting with NAME. A bare name was a prefix
// until it selected seven methods for "fit_scales" (tips, tissue and the NLopt optimisers too).
bool methodSelected(const std::string& name, const std::string& tag) {
  if (!name.empty() && name.back() == '*')
    return tag.rfind(name.substr(0, name.size() - 1), 0) == 0;
  return tag == name || (tag.rfind("fit_", 0) == 0 && tag == name + "_ceres");
}

// The plan restricted to the jobs of the chosen methods and seeds, and the cases they use.
ExperimentPlan restrictPlan(const ExperimentPlan& plan, const std::vector<std::string>& methods,
                            const std::vector<int>& seeds, const std::vector<std::string>& presets,
                            const std::vector<std::string>& cases) {
  if (methods.empty() && seeds.empty() && presets.empty() && cases.empty()) return plan;
  // Every name given must name something of the plan: a typo in a list used to drop that item
  // without a word (`--presets normal-1,nosuch` ran normal-1 alone).
  std::set<std::string> known_presets, known_cases, known_seeds, known_methods;
  for (const CaseSpec& c : plan.cases) {
    known_presets.insert(c.preset);
    known_cases.insert(c.id);
    known_seeds.insert(std::to_string(c.seed));
  }
  for (const JobSpec& job : plan.jobs) known_methods.insert(methodTag(job));
  auto refuseUnknown = [](const char* option, const std::vector<std::string>& given,
                          const std::set<std::string>& known, bool methods) {
    for (const std::string& name : given) {
      const bool found =
          methods ? std::any_of(known.begin(), known.end(),
                                [&](const std::string& k) { return methodSelected(name, k); })
                  : known.count(name) > 0;
      if (found) continue;
      std::string list;
      for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
      throw std::invalid_argument(
          std::string(option) + ": \"" + name + "\" is not one of the plan's: " + list +
          (methods ? " (a Ceres fit also without _ceres; NAME* selects every method starting "
                     "with NAME)"
                   : ""));
    }
  };
  std::vector<std::string> seed_names;
  for (int seed : seeds) seed_names.push_back(std::to_string(seed));
  refuseUnknown("--methods", methods, known_methods, true);
  refuseUnknown("--seeds", seed_names, known_seeds, false);
  refuseUnknown("--presets", presets, known_presets, false);
  refuseUnknown("--cases", cases, known_cases, false);
  ExperimentPlan kept;
  for (const JobSpec& job : plan.jobs) {
    const CaseSpec& c = findCase(plan, job.case_id);
    if (!seeds.empty() && std::find(seeds.begin(), seeds.end(), c.seed) == seeds.end()) continue;
    if (!presets.empty() && std::find(presets.begin(), presets.end(), c.preset) == presets.end()) {
      continue;
    }
    if (!cases.empty() && std::find(cases.begin(), cases.end(), c.id) == cases.end()) continue;
    bool method = methods.empty();
    for (const std::string& m : methods) method |= methodSelected(m, methodTag(job));
    if (method) kept.jobs.push_back(job);
  }
  for (const CaseSpec& c : plan.cases) {
    for (const JobSpec& job : kept.jobs) {
      if (job.case_id == c.id) {
        kept.cases.push_back(c);
        break;
      }
    }
  }
  if (kept.jobs.empty()) {
    throw std::invalid_argument(
        "--methods / --seeds / --presets / --cases: each names part of the plan, but no job "
        "matches all of them together");
  }
  return kept;
}

// The first of `jobs` whose result in `results` records other options than this run asks
// (resultOptionMismatch), with how many of them do.
struct StaleResult {
  const JobSpec* job = nullptr;
  fs::path file;
  OptionMismatch mismatch;
  int count = 0;
};
StaleResult staleResults(const ExperimentPlan& plan, const ExperimentConfig& config,
                         const std::vector<const JobSpec*>& jobs, const fs::path& results) {
  StaleResult stale;
  for (const JobSpec* job : jobs) {
    const fs::path file = results / "jobs" / (job->id + ".json");
    std::string text;
    if (!chordfit::readWholeFile(file, text)) continue;
    const auto result = nlohmann::json::parse(text, nullptr, false);
    if (result.is_discarded()) continue;  // merge names the file it cannot read
    const auto mismatch = resultOptionMismatch(result, *job, findCase(plan, job->case_id), config);
    if (!mismatch) continue;
    if (stale.count++ == 0) stale = {job, file, *mismatch, 1};
  }
  return stale;
}

// "max_sims 300, the run asks for 150 (--max-sims)".
std::string describe(const OptionMismatch& m, const char* who, const std::string& plan) {
  return m.field + " " + m.recorded + ", " + who + " " + m.requested + " (" + m.option + ")" +
         otherPlanHint(m, plan);
}

std::string moreLikeIt(int count, const char* what) {
  if (count < 2) return "";
  return " (" + std::to_string(count - 1) + " more " + what + (count > 2 ? "s" : "") + " like it)";
}

// The same over every job of the plan (merge and check: the tables are of all of them).
StaleResult staleResultsOfPlan(const ExperimentPlan& plan, const ExperimentConfig& config,
                               const fs::path& results) {
  std::vector<const JobSpec*> jobs;
  for (const JobSpec& job : plan.jobs) jobs.push_back(&job);
  return staleResults(plan, config, jobs, results);
}

// "job ID was run with other options: FILE records max_sims 300, WHO 150 (--max-sims) (2 more
// jobs like it)", for merge and check.
std::string staleJobText(const StaleResult& stale, const char* who, const std::string& plan) {
  return "job " + stale.job->id + " was run with other options: " + stale.file.string() +
         " records " + describe(stale.mismatch, who, plan) + moreLikeIt(stale.count, "job");
}

// "" when `dir` exists or can be made and a file can be written in it; else what stands in the
// way. Checked before the first job: a read-only results directory was found only when the
// first job's result could not be written, after its fit, and the shard ended there.
std::string unwritableDirectory(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return dir.string() + ": cannot be made (" + ec.message() + ")";
  const fs::path probe = dir / (".write-test-" + std::to_string(::getpid()));
  {
    std::ofstream out(probe);
    if (!out) return dir.string() + ": cannot be written to (" + std::strerror(errno) + ")";
  }
  fs::remove(probe, ec);
  return "";
}

// Before a run starts: a present case or result made with other options than this run's would
// be reused as if it were made with them (a case whatever --force says, a result unless
// --force). Returns the message refusing the run, or "".
std::string refuseStaleInputs(const ExperimentPlan& plan, const ExperimentConfig& config,
                              const Arguments& a, const RunPaths& paths,
                              const std::vector<const CaseSpec*>& cases,
                              const std::vector<const JobSpec*>& jobs) {
  std::vector<const CaseSpec*> used = cases;
  for (const JobSpec* job : jobs) {
    const CaseSpec* c = &findCase(plan, job->case_id);
    if (std::find(used.begin(), used.end(), c) == used.end()) used.push_back(c);
  }
  int stale_cases = 0;
  std::string first;
  for (const CaseSpec* c : used) {
    const fs::path dir = caseDirectory(paths, c->id);
    if (!fs::exists(dir / "case.json")) continue;
    const auto mismatch = caseOptionMismatch(*c, dir);
    if (mismatch && stale_cases++ == 0) {
      first = "case " + c->id + " in " + dir.string() + " was made with " +
              describe(*mismatch, "this run asks for", a.plan);
    }
  }
  if (stale_cases > 0) {
    return first + moreLikeIt(stale_cases, "case") +
           ". Give another --work (and --results) for these options, or remove the case "
           "directory (--force reruns jobs, it does not remake cases)";
  }
  if (a.force) return "";
  const StaleResult stale = staleResults(plan, config, jobs, a.results);
  if (stale.count == 0) return "";
  return "job " + stale.job->id + " has a result made with other options: " + stale.file.string() +
         " records " + describe(stale.mismatch, "this run asks for", a.plan) +
         moreLikeIt(stale.count, "job") +
         ". Rerun them with --force (their results are replaced), or give another --results "
         "(and --work) for these options";
}

const char* signalName(int signal_number) {
  return signal_number == SIGINT    ? "SIGINT"
         : signal_number == SIGTERM ? "SIGTERM"
         : signal_number == SIGHUP  ? "SIGHUP"
                                    : "a signal";
}

// The command that resumes a stopped run: this one (jobs with a result are kept, so what
// finished is not run again). A --force run keeps --force: the jobs it did not reach still
// hold results from before it (another revision, perhaps), which a resume without it would
// keep beside the new ones; so it runs every selected job again, the finished ones too.
std::string resumeCommand(const Arguments& a) {
  std::string line;
  for (const std::string& arg : a.command_line) {
    const bool plain = !arg.empty() && arg.find_first_of(" '\"\\$*?&;|<>()") == std::string::npos;
    line += (line.empty() ? "" : " ") + (plain ? arg : "'" + arg + "'");
  }
  return line;
}

// Ends a run that was asked to stop: says what finished and how to resume. Returns the exit
// code, 128 + the signal (130 for SIGINT, 143 for SIGTERM), as a shell reports a process killed
// by it.
// Jobs and cases are counted apart: a case that failed to generate is not one of the jobs.
int stopRun(const Arguments& a, int signal_number, const std::string& during,
            const std::vector<std::string>& finished, int present, std::size_t jobs,
            std::size_t failures, std::size_t case_failures, double seconds) {
  const std::size_t done = finished.size() + static_cast<std::size_t>(present);
  std::fprintf(stderr,
               "run_experiments: stopped by %s %s after %.0f s; a step stopped midway writes "
               "nothing (its chordfit was stopped and waited for; results are written whole or "
               "not at all)\n",
               signalName(signal_number), during.c_str(), seconds);
  std::fprintf(stderr,
               "run_experiments: this run finished %zu job(s) with a result (%d were there "
               "already), %zu failed, %zu of the shard's %zu not done\n",
               finished.size(), present, failures, jobs - std::min(jobs, done + failures), jobs);
  if (case_failures > 0)
    std::fprintf(stderr, "run_experiments: and %zu case(s) failed to generate\n", case_failures);
  for (std::size_t i = 0; i < finished.size() && i < kListedAtMost; ++i)
    std::fprintf(stderr, "  finished: %s\n", finished[i].c_str());
  if (finished.size() > kListedAtMost)
    std::fprintf(stderr, "  ... and %zu more\n", finished.size() - kListedAtMost);
  std::fprintf(stderr, "run_experiments: resume with: %s\n", resumeCommand(a).c_str());
  if (a.force)
    std::fprintf(stderr,
                 "run_experiments: (--force kept: the jobs this run did not reach still hold "
                 "results from before it, which a resume without --force would keep; it runs "
                 "the finished jobs again too, or select the rest with --cases/--methods)\n");
  return kExitSignalBase + signal_number;
}

int runShard(const ExperimentPlan& plan, const ExperimentConfig& config, const Arguments& a) {
  const RunPaths paths{a.chordfit,           a.results,    a.work, chordfitRevision(a.chordfit),
                       machineDescription(), a.case_source};
  const auto start = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  std::vector<std::string> failures;
  // Cases first (round-robin like the jobs), so a shard's jobs rarely wait on generation.
  std::vector<const CaseSpec*> cases;
  for (std::size_t k = 0; k < plan.cases.size(); ++k) {
    if (inShard(k, a.shard)) cases.push_back(&plan.cases[k]);
  }
  std::vector<const JobSpec*> jobs;
  for (std::size_t k = 0; k < plan.jobs.size(); ++k) {
    if (inShard(k, a.shard)) jobs.push_back(&plan.jobs[k]);
  }
  if (const std::string refusal = refuseStaleInputs(plan, config, a, paths, cases, jobs);
      !refusal.empty()) {
    std::fprintf(stderr, "run_experiments: error: %s\n", refusal.c_str());
    return kExitUsage;
  }
  // A missing chordfit failed every case and job in turn ("6 failure(s)" for 2 cases, 4 jobs).
  if (!fs::is_regular_file(a.chordfit) || ::access(a.chordfit.c_str(), X_OK) != 0) {
    std::fprintf(stderr, "run_experiments: error: --chordfit %s: %s (build it, or give its path)\n",
                 a.chordfit.c_str(),
                 !fs::exists(a.chordfit)            ? "no such file"
                 : !fs::is_regular_file(a.chordfit) ? "not a file"
                                                    : "not executable");
    return kExitUsage;
  }
  if (const std::string problem = unwritableDirectory(a.results / "jobs"); !problem.empty()) {
    std::fprintf(stderr, "run_experiments: error: --results: %s\n", problem.c_str());
    return kExitUsage;
  }
  if (const std::string problem = unwritableDirectory(a.work); !problem.empty()) {
    std::fprintf(stderr, "run_experiments: error: --work: %s\n", problem.c_str());
    return kExitUsage;
  }
  std::fprintf(stderr, "run_experiments: shard %d/%d: %zu of %zu cases, %zu of %zu jobs\n",
               a.shard.index, a.shard.count, cases.size(), plan.cases.size(), jobs.size(),
               plan.jobs.size());
  // In full: the defaults are the build's source tree, not the working directory.
  auto full = [](const fs::path& p) {
    std::error_code ec;
    const fs::path absolute = fs::absolute(p, ec);
    return (ec ? p : absolute.lexically_normal()).string();
  };
  std::fprintf(stderr, "run_experiments: results in %s, work in %s, chordfit %s (revision %s)\n",
               full(a.results).c_str(), full(a.work).c_str(), full(a.chordfit).c_str(),
               paths.revision.c_str());
  if (jobs.empty())
    std::fprintf(stderr,
                 "run_experiments: note: shard %d/%d holds none of the plan's %zu job(s) (fewer "
                 "jobs than shards); nothing to run here\n",
                 a.shard.index, a.shard.count, plan.jobs.size());
  // A stop (Ctrl-C, kill, or a chordfit that died of SIGINT / SIGTERM) ends the whole run: it
  // used to be logged as one failed job, and the next job started.
  std::vector<std::string> finished;  // jobs that ran to a result in this run
  int present = 0;
  std::size_t case_failures = 0;  // of `failures`, the cases' (the rest are jobs)
  auto stopped = [&](const StepOutcome* o, const std::string& during) {
    const int signal_number = o && o->stop_signal ? o->stop_signal : stopSignal();
    return signal_number == 0 ? kExitOk
                              : stopRun(a, signal_number, during, finished, present, jobs.size(),
                                        failures.size() - case_failures, case_failures, elapsed());
  };
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const std::string step = "case " + std::to_string(k + 1) + "/" + std::to_string(cases.size()) +
                             " (" + cases[k]->id + ")";
    if (const int code = stopped(nullptr, "before " + step)) return code;
    std::fprintf(stderr, "[case %zu/%zu] %s: generating unless present...\n", k + 1, cases.size(),
                 cases[k]->id.c_str());
    const StepOutcome o = ensureCase(*cases[k], paths);
    if (o.ok) {
      std::fprintf(stderr, "[case %zu/%zu] %s: %s (%.0f s elapsed)\n", k + 1, cases.size(),
                   cases[k]->id.c_str(), o.summary.c_str(), elapsed());
    } else if (o.stop_signal == 0) {
      std::fprintf(stderr, "[case %zu/%zu] FAILED %s\n", k + 1, cases.size(), o.error.c_str());
      failures.push_back(o.error);
      ++case_failures;
    }
    if (const int code = stopped(&o, (o.ok ? "after " : "during ") + step)) return code;
  }
  for (std::size_t k = 0; k < jobs.size(); ++k) {
    const JobSpec& job = *jobs[k];
    const std::string step =
        "job " + std::to_string(k + 1) + "/" + std::to_string(jobs.size()) + " (" + job.id + ")";
    if (const int code = stopped(nullptr, "before " + step)) return code;
    std::fprintf(stderr, "[job %zu/%zu] %s: running...\n", k + 1, jobs.size(), job.id.c_str());
    const StepOutcome o = runJob(plan, config, job, paths, a.force);
    if (o.ok) {
      std::fprintf(stderr, "[job %zu/%zu] %s: %s (%.0f s elapsed)\n", k + 1, jobs.size(),
                   job.id.c_str(), o.summary.c_str(), elapsed());
      if (o.skipped)
        ++present;
      else
        finished.push_back(job.id);
    } else if (o.stop_signal == 0) {
      std::fprintf(stderr, "[job %zu/%zu] FAILED %s\n", k + 1, jobs.size(), o.error.c_str());
      failures.push_back(o.error);
    }
    if (const int code = stopped(&o, (o.ok ? "after " : "during ") + step)) return code;
  }
  std::fprintf(stderr, "run_experiments: shard %d/%d done in %.0f s, %zu failure(s)\n",
               a.shard.index, a.shard.count, elapsed(), failures.size());
  for (const std::string& f : failures) std::fprintf(stderr, "  failed: %s\n", f.c_str());
  return failures.empty() ? kExitOk : kExitJobsFailed;
}

// The options that chose the plan's cases and jobs, as given on the command line, then the
// budget, edge and bounds where they are not the plan's defaults (nonDefaultOptions,
// Arguments::option_values: they change the numbers, not which rows exist).
std::string planOptions(const Arguments& a) {
  std::string text = "--plan " + a.plan;
  auto list = [&](const char* option, const std::vector<std::string>& items) {
    if (items.empty()) return;
    text += std::string(" ") + option + " ";
    for (std::size_t i = 0; i < items.size(); ++i) text += (i ? "," : "") + items[i];
  };
  list("--methods", a.methods);
  std::vector<std::string> seeds;
  for (int seed : a.seeds) seeds.push_back(std::to_string(seed));
  list("--seeds", seeds);
  list("--presets", a.presets);
  list("--cases", a.cases);
  if (!a.option_values.empty()) text += " " + a.option_values;
  return text;
}

// The plan options and plan id index.md records (merges since they were recorded), or "".
struct RecordedPlan {
  std::string options, id;
};
RecordedPlan recordedPlan(const fs::path& results) {
  std::ifstream in(results / "index.md");
  const std::string prefix = std::string(kPlanOptionsLine) + "`";
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) != 0) continue;
    const std::size_t mark = line.find(kPlanIdMark);
    if (mark == std::string::npos || line.back() != '`') return {};
    const std::size_t id_at = mark + std::string(kPlanIdMark).size();
    return {line.substr(prefix.size(), mark - 1 - prefix.size()),
            line.substr(id_at, line.size() - 1 - id_at)};
  }
  return {};
}

int merge(const ExperimentPlan& plan, const ExperimentConfig& config, const Arguments& a) {
  // A mistyped --results used to be created and filled with empty tables.
  if (std::error_code ec; !fs::is_directory(a.results / "jobs", ec)) {
    std::fprintf(stderr,
                 "run_experiments: error: merge: %s: no such directory (the jobs' results; run "
                 "them first with `run_experiments run`, or give the --results they went to)\n",
                 (a.results / "jobs").string().c_str());
    return kExitUsage;
  }
  // Tables labelled with options the jobs were not run with (a --max-sims 150 merge of jobs
  // that used 300) used to be written without a word.
  if (const StaleResult stale = staleResultsOfPlan(plan, config, a.results); stale.count > 0) {
    std::fprintf(stderr,
                 "run_experiments: error: merge: %s. Merge with the options the jobs were run "
                 "with, or rerun them with these (run --force); nothing was written\n",
                 staleJobText(stale, "the merge asks for", a.plan).c_str());
    return kExitUsage;
  }
  const MergeSummary s = mergeResults(plan, config, a.results,
                                      {a.no_timing, planOptions(a), planId(plan, a.option_values)});
  std::printf("merged %d of %zu job results into %s:", s.jobs_found, plan.jobs.size(),
              a.results.string().c_str());
  for (const std::string& f : s.written_files) std::printf(" %s", f.c_str());
  std::printf("\n");
  if (s.missing_jobs.empty()) return kExitOk;
  std::fprintf(stderr, "%s: %zu job(s) without a result (no rows for them):\n",
               a.allow_missing ? "warning" : "error", s.missing_jobs.size());
  // A few by name; a long list is in index.md.
  for (std::size_t i = 0; i < s.missing_jobs.size() && i < kListedAtMost; ++i)
    std::fprintf(stderr, "  %s\n", s.missing_jobs[i].c_str());
  if (s.missing_jobs.size() > kListedAtMost)
    std::fprintf(stderr, "  ... and %zu more (listed in %s)\n",
                 s.missing_jobs.size() - kListedAtMost, (a.results / "index.md").string().c_str());
  return a.allow_missing ? kExitOk : kExitJobsFailed;
}

std::vector<std::vector<std::string>> readCsv(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return chordfit::parseSimpleCsv(text.str());
}

// Every table exists, has the documented header, rows of the header's width, and one Table 1
// row per planned Table 1 job (plus a noise-floor row per truth job) with an AvgD.
int check(const ExperimentPlan& plan, const ExperimentConfig& config, const Arguments& a) {
  if (std::error_code ec; !fs::is_directory(a.results, ec)) {
    std::fprintf(stderr, "check: %s: no such directory (give the --results of the merge)\n",
                 a.results.string().c_str());
    std::printf("check: FAILED (%s)\n", a.results.string().c_str());
    return kExitJobsFailed;
  }
  std::vector<std::string> problems;
  // Job results made with other options than the check's (the tables would be of those).
  if (const StaleResult stale = staleResultsOfPlan(plan, config, a.results); stale.count > 0) {
    std::fprintf(stderr, "check: %s: give check the options the jobs were run with\n",
                 staleJobText(stale, "the check asks for", a.plan).c_str());
    std::printf("check: FAILED (%s)\n", a.results.string().c_str());
    return kExitJobsFailed;
  }
  // Results of another plan (the smoke run's, checked against the full plan) would list every
  // job of this plan as missing: say so once instead.
  // The plans are compared by their jobs, not by the options' text: "--seeds 1,2,3" is the full
  // plan, and the order of names does not matter.
  if (const RecordedPlan made = recordedPlan(a.results);
      !made.id.empty() && made.id != planId(plan, a.option_values)) {
    std::fprintf(stderr,
                 "check: %s was merged with `%s`, another plan than this check's `%s`: give "
                 "check the options of the merge\n",
                 a.results.string().c_str(), made.options.c_str(), planOptions(a).c_str());
    std::printf("check: FAILED (%s)\n", a.results.string().c_str());
    return kExitJobsFailed;
  }
  auto header = [](const std::string& h) { return h.substr(0, h.size() - 1); };
  struct Table {
    const char* file;
    std::string header;
  };
  const bool timing = [&] {
    const auto rows = readCsv(a.results / "table1.csv");
    return !rows.empty() && !rows[0].empty() && rows[0].back() == "wall_seconds";
  }();
  // Which tables the plan's jobs fill: a subset (--presets, --cases, --seeds, --methods) may
  // hold none of a table's source jobs, and then the table has no rows by design.
  const int first_seed = config.seeds.front();
  std::set<std::string> heuristic_cases, fit_cases;
  bool fills_optimizers = false, fills_sensitivity = false, fills_recovery = false;
  for (const JobSpec& job : plan.jobs) {
    const std::string tag = methodTag(job);
    if (tag == "heuristic") heuristic_cases.insert(job.case_id);
    if (tag == "fit_scales_ceres") fit_cases.insert(job.case_id);
    fills_recovery |= tag != "truth";
    for (const std::string& preset : config.optimizer_presets)
      fills_optimizers |=
          job.case_id == baseCaseId(preset, first_seed) && tag.rfind("fit_scales_", 0) == 0;
    fills_sensitivity |= job.case_id == baseCaseId(config.sensitivity_preset, first_seed) &&
                         (tag == "heuristic" || tag == "fit_scales_ceres" || tag == "truth");
  }
  bool fills_acceptance = false;
  for (const std::string& id : fit_cases) fills_acceptance |= heuristic_cases.count(id) > 0;
  const std::vector<Table> tables = {{"table1.csv", header(table1CsvHeader(timing))},
                                     {"acceptance.csv", header(acceptanceCsvHeader(timing))},
                                     {"optimizers.csv", header(optimizersCsvHeader(timing))},
                                     {"recovery.csv", header(recoveryCsvHeader())},
                                     {"sensitivity.csv", header(sensitivityCsvHeader())}};
  for (const Table& t : tables) {
    const auto rows = readCsv(a.results / t.file);
    if (rows.empty()) {
      problems.push_back(std::string(t.file) + ": missing or empty");
      continue;
    }
    std::string got;
    for (const std::string& c : rows[0]) got += (got.empty() ? "" : ",") + c;
    if (got != t.header) problems.push_back(std::string(t.file) + ": header \"" + got + "\"");
    const std::string file = t.file;
    const bool optional = (file == "acceptance.csv" && !fills_acceptance) ||
                          (file == "optimizers.csv" && !fills_optimizers) ||
                          (file == "recovery.csv" && !fills_recovery) ||
                          (file == "sensitivity.csv" && !fills_sensitivity);
    if (rows.size() < 2 && !optional) problems.push_back(std::string(t.file) + ": no data rows");
    for (std::size_t r = 1; r < rows.size(); ++r) {
      if (rows[r].size() != rows[0].size()) {
        problems.push_back(std::string(t.file) + ": row " + std::to_string(r) + " has " +
                           std::to_string(rows[r].size()) + " cells, header " +
                           std::to_string(rows[0].size()));
      }
    }
  }
  for (const char* file :
       {"table1.md", "acceptance.md", "optimizers.md", "optimizers.svg", "recovery.md",
        "recovery.svg", "recovery_cords.csv", "sensitivity.md", "sensitivity.svg", "index.md"}) {
    if (!fs::exists(a.results / file)) problems.push_back(std::string(file) + ": missing");
  }
  // One row per table-1 job of the preset x seed cases (with a mean deviation).
  const auto rows = readCsv(a.results / "table1.csv");
  std::vector<std::string> without_row;
  int table1_jobs = 0;
  for (const JobSpec& job : plan.jobs) {
    if (job.method == Method::kFit && job.optimizer != "ceres") continue;
    const std::string tag = methodTag(job);
    bool base_case = false;
    for (const CaseSpec& c : plan.cases) {
      base_case |= c.id == job.case_id && c.id == baseCaseId(c.preset, c.seed);
    }
    if (!base_case) continue;
    ++table1_jobs;
    bool found = false;
    for (std::size_t r = 1; r < rows.size(); ++r) {
      found |= rows[r].size() > 9 && rows[r][0] == job.case_id && rows[r][3] == tag &&
               !rows[r][9].empty();
    }
    if (!found) {
      without_row.push_back(job.id);
      continue;
    }
    // A row whose result file is gone or unusable (a rerun that failed, an edited file): the
    // tables are older than the jobs.
    const fs::path file = a.results / "jobs" / (job.id + ".json");
    if (!fs::exists(file)) {
      problems.push_back("table1.csv: the row of job " + job.id + " has no result file " +
                         file.string() + " (gone since the merge: run the job, then merge)");
    } else if (const std::string problem = jobResultProblem(file, job.id); !problem.empty()) {
      problems.push_back("table1.csv: the row of job " + job.id + " is of " + file.string() +
                         ", which " + problem);
    }
  }
  if (without_row.size() <= kListedAtMost) {
    for (const std::string& id : without_row)
      problems.push_back("table1.csv: no row with an AvgD for job " + id);
  } else {
    std::string examples;
    for (std::size_t i = 0; i < 3; ++i) examples += (i ? ", " : "") + without_row[i];
    problems.push_back("table1.csv: no row with an AvgD for " + std::to_string(without_row.size()) +
                       " of the plan's " + std::to_string(table1_jobs) + " Table 1 jobs (" +
                       examples + ", ...; `run_experiments list` prints the plan)");
  }
  for (const std::string& p : problems) std::fprintf(stderr, "check: %s\n", p.c_str());
  std::printf("check: %s (%s)\n", problems.empty() ? "ok" : "FAILED", a.results.string().c_str());
  return problems.empty() ? kExitOk : kExitJobsFailed;
}

int list(const ExperimentPlan& plan, const Arguments& a) {
  for (std::size_t k = 0; k < plan.cases.size(); ++k) {
    const CaseSpec& c = plan.cases[k];
    if (!inShard(k, a.shard)) continue;
    std::printf("case %-32s preset %s seed %d planes %d noise %g dropout %g edge %g\n",
                c.id.c_str(), c.preset.c_str(), c.seed, c.planes, c.noise_mm, c.dropout, c.edge_mm);
  }
  for (std::size_t k = 0; k < plan.jobs.size(); ++k) {
    if (inShard(k, a.shard)) std::printf("job  %s\n", plan.jobs[k].id.c_str());
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments a;
  if (const int code = parseArguments(argc, argv, a); code != kExitOk) return code;
  const ExperimentConfig defaults = a.plan == "smoke"     ? smokeConfig()
                                    : a.plan == "reduced" ? reducedConfig()
                                                          : fullConfig();
  ExperimentConfig config = defaults;
  if (a.max_sims > 0) config.max_sims = a.max_sims;
  if (a.edge_mm > 0.0) config.edge_mm = a.edge_mm;
  if (a.scale_bounds) config.scale_bounds = a.scale_bounds;
  ExperimentPlan plan;
  try {
    plan = restrictPlan(makePlan(config), a.methods, a.seeds, a.presets, a.cases);
  } catch (const std::invalid_argument& e) {  // a filter that matches nothing: usage
    return usageError(e.what());
  }
  a.option_values = nonDefaultOptions(config, defaults, plan);
  if (!a.methods.empty()) {
    std::vector<std::string> selected;
    for (const JobSpec& job : plan.jobs) {
      const std::string tag = methodTag(job);
      if (std::find(selected.begin(), selected.end(), tag) == selected.end())
        selected.push_back(tag);
    }
    std::fprintf(stderr, "run_experiments: --methods selects %zu method(s): %s\n", selected.size(),
                 joined(selected, ", ").c_str());
  }
  try {
    if (a.command == "list") return list(plan, a);
    if (a.command == "merge") return merge(plan, config, a);
    if (a.command == "check") return check(plan, config, a);
    installStopHandlers();
    const int ran = runShard(plan, config, a);
    restoreDefaultStopHandlers();
    if (a.command == "run" || ran > kExitSignalBase) return ran;  // stopped: no merge
    const int merged = merge(plan, config, a);
    if (a.smoke) {
      const int checked = check(plan, config, a);
      if (checked != kExitOk) return checked;
    }
    return ran != kExitOk && !a.allow_missing ? ran : merged;
  } catch (const std::exception& e) {
    std::cerr << "run_experiments: error: " << e.what() << "\n";
    return kExitJobsFailed;
  }
}
