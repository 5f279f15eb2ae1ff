// `merge`: the tables and plots of the benchmark experiments, from the per-job results
// (<results>/jobs/*.json) of the plan's jobs. Reads nothing else, so shards run anywhere can
// be merged by copying their jobs/ directories together. Writes, atomically:
//   table1.md/.csv       the paper's Table 1 per case and method, plus forward sims and wall s
//   acceptance.md/.csv   issue 5's acceptance criteria per case (acceptance_table.h)
//   optimizers.md/.csv   final AvgD, sims to within 10 % of the best, wall s; optimizers.svg
//   recovery.md/.csv     rest-length error vs truth by attachment distance from the nearest
//                        tracing plane; recovery_cords.csv (per cord), recovery.svg
//   sensitivity.md/.csv  AvgD and recovery error against tracing noise and plane count;
//                        sensitivity.svg
//   index.md             what ran, from which revision, and which jobs are missing
// A job without a result (failed or not run) gives no row; it is listed under "Missing".
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "experiments/experiment_plan.h"

namespace chordfit::experiments {

struct MergeOptions {
  // Leave out wall-time columns (the only part of the results that differs between runs),
  // so that two runs can be compared with diff.
  bool no_timing = false;
  // The run_experiments options that chose the plan (e.g. "--plan smoke --methods fit"),
  // recorded in index.md with the plan's id (planId) so that `check` can tell results of
  // another plan from missing rows.
  std::string plan_options;
  // planId(plan, the options' non-default values) recorded beside them; "" for planId(plan).
  std::string plan_id;
};

// index.md's line recording MergeOptions::plan_options and the plan id:
// "Plan options: `--plan smoke`; plan id `0123456789abcdef`".
constexpr const char* kPlanOptionsLine = "Plan options: ";
constexpr const char* kPlanIdMark = "; plan id `";

struct MergeSummary {
  int jobs_found = 0;
  std::vector<std::string> missing_jobs;
  std::vector<std::string> written_files;
};

// The CSV headers of the tables (the smoke run checks them).
std::string table1CsvHeader(bool timing);
std::string optimizersCsvHeader(bool timing);
std::string recoveryCsvHeader();
std::string sensitivityCsvHeader();

MergeSummary mergeResults(const ExperimentPlan& plan, const ExperimentConfig& config,
                          const std::filesystem::path& results, const MergeOptions& options);

}  // namespace chordfit::experiments
