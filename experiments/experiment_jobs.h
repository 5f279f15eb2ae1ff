// Running the plan's cases and jobs through the `chordfit` command-line program.
//   case  `chordfit make-case` into <work>/cases/<id>, generated in a private directory and
//         renamed into place, so shards that need the same case never see half of one (the
//         generator is deterministic: whichever shard wins, the files are the same);
//   job   one method on one case in <work>/runs/<job id>; its result, a small JSON file, goes
//         to <results>/jobs/<job id>.json and is written only when the job succeeded. A failed
//         job (missing command, bad exit code, missing output) writes no result: it is reported
//         and `merge` lists it as missing, so no table row is ever made up.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "experiments/experiment_plan.h"

namespace chordfit::experiments {

struct RunPaths {
  std::filesystem::path chordfit;  // the chordfit executable
  std::filesystem::path results;   // tables, plots, jobs/*.json (committed)
  std::filesystem::path work;      // cases and run directories (not committed)
  std::string revision;            // source revision, recorded in every job result
  std::string machine;             // CPU model and logical CPUs, recorded in every job result
  // Optional: directory of already generated cases (e.g. build/cases). A case whose
  // truth/truth.json records the same preset, seed, edge, planes, noise and dropout is copied
  // instead of generated: make-case is deterministic, so the copy equals a fresh case as long
  // as the generator and simulator have not changed since it was made.
  std::filesystem::path case_source;
};

struct StepOutcome {
  bool ok = false;
  bool skipped = false;  // already done (case present, result present)
  std::string error;     // when !ok: what failed and where its log is
  std::string summary;   // one line for the progress output when ok
  // When !ok because the run is to stop: SIGINT or SIGTERM, which its chordfit died of (or
  // exit code 130 / 143, chordfit's own way of dying of them) or run_experiments received.
  int stop_signal = 0;
};

// Stopping a run (Ctrl-C, `kill`): SIGINT and SIGTERM are forwarded to the running chordfit,
// which writes nothing when interrupted; its step then fails with stop_signal set, no result is
// written, and stopSignal() tells the caller to start nothing more. Call once, before running.
void installStopHandlers();
// Back to the default (a signal ends the process): after the jobs, when a merge or check runs,
// a Ctrl-C should stop it, not be recorded for a run that is over.
void restoreDefaultStopHandlers();
// 0, or the SIGINT / SIGTERM run_experiments received since installStopHandlers.
int stopSignal();

// An option a job result or a case records that differs from what the run asks of it.
struct OptionMismatch {
  std::string field;      // the recorded key: "max_sims", "edge_mm", "generation.planes", ...
  std::string option;     // what sets it: "--max-sims", "--edge", "--scale-bounds", "--plan"
  std::string recorded;   // "300"; "the fit's default" for a fit without scale_bounds
  std::string requested;  // the same for this run's options
};

// " (--plan smoke's value: were these made with --plan smoke?)" when the recorded value of
// `m` is another plan's default (full, reduced, smoke) and not that of `plan`; else "". Results
// of the smoke plan checked without it read as another --edge, and the user reached for --edge.
std::string otherPlanHint(const OptionMismatch& m, const std::string& plan);

// The first option a job result records that differs from what `spec` and `config` ask of
// `job`: the case's edge_mm, planes, noise_mm and dropout, and a fit's max_sims and
// scale_bounds (absent: the fit's default bounds). A key an older result does not record is not
// compared. nullopt when every recorded option agrees.
std::optional<OptionMismatch> resultOptionMismatch(const nlohmann::json& result, const JobSpec& job,
                                                   const CaseSpec& spec,
                                                   const ExperimentConfig& config);

// The first generation option of the case in `case_dir` (truth/truth.json: preset, seed,
// case_edge_mm, planes, noise_mm, dropout_fraction, truth_edge_mm) that differs from `spec`;
// a truth.json that is missing, not JSON or without the key is a mismatch too. nullopt when the
// case was made with `spec`'s options.
std::optional<OptionMismatch> caseOptionMismatch(const CaseSpec& spec,
                                                 const std::filesystem::path& case_dir);

std::filesystem::path caseDirectory(const RunPaths& paths, const std::string& case_id);
std::filesystem::path jobResultPath(const RunPaths& paths, const std::string& job_id);

// Generates (or copies from case_source) the case unless <work>/cases/<id>/case.json exists
// (run_experiments refuses, before it starts, a present case made with other options:
// caseOptionMismatch).
StepOutcome ensureCase(const CaseSpec& spec, const RunPaths& paths);

// Runs the job unless its result exists (or `force`), generating its case when missing
// (run_experiments refuses, before it starts, a present result made with other options unless
// `force`: resultOptionMismatch).
StepOutcome runJob(const ExperimentPlan& plan, const ExperimentConfig& config, const JobSpec& job,
                   const RunPaths& paths, bool force);

}  // namespace chordfit::experiments
