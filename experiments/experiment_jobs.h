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
#include <string>

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
};

std::filesystem::path caseDirectory(const RunPaths& paths, const std::string& case_id);
std::filesystem::path jobResultPath(const RunPaths& paths, const std::string& job_id);

// Generates (or copies from case_source) the case unless <work>/cases/<id>/case.json exists.
StepOutcome ensureCase(const CaseSpec& spec, const RunPaths& paths);

// Runs the job unless its result exists (or `force`), generating its case when missing.
StepOutcome runJob(const ExperimentPlan& plan, const ExperimentConfig& config, const JobSpec& job,
                   const RunPaths& paths, bool force);

}  // namespace chordfit::experiments
