// Issue 5's acceptance criteria on the synthetic cohort, per Table 1 case, from the merged job
// results: the per-cord Ceres fit from the heuristic
//   - reduces AvgD by at least 40 % against the heuristic (pathological presets),
//   - ends within 1.5x the noise floor (truth/metrics.json mean),
//   - reconstructs the prolapse (simulated segments = the tracings' segments),
//   - recovers the true rest lengths of cords attached within 3 mm of a tracing plane to a
//     median |error| <= 3 %.
// Alongside, what the case mesh allows: AvgD of the true cords closed on the case mesh (the
// `truth` job), whose excess over the noise floor no fit of this mesh can remove.
// Written by `merge` as acceptance.md / acceptance.csv.
#pragma once

#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "experiments/experiment_plan.h"

namespace chordfit::experiments {

struct AcceptanceThresholds {
  double min_reduction_pct = 40.0;
  double max_over_noise_floor = 1.5;
  double max_recovery_median_pct = 3.0;
  double near_plane_mm = 3.0;
};

struct AcceptanceTables {
  std::string markdown, csv;
};

// result(case_id, method tag): the job's result, or nullptr when it has none.
using ResultLookup =
    std::function<const nlohmann::json*(const std::string& case_id, const std::string& tag)>;

// planned(case_id, method tag): the merge's plan holds that job. A case whose heuristic or
// per-cord Ceres fit is not planned (a subset's --cases, --methods) is left out without a word;
// one whose planned jobs have no result is named as not judged.
using PlanLookup = std::function<bool(const std::string& case_id, const std::string& tag)>;

AcceptanceTables acceptanceTables(const ExperimentConfig& config, const ResultLookup& result,
                                  const PlanLookup& planned, bool timing,
                                  const AcceptanceThresholds& thresholds = {});

std::string acceptanceCsvHeader(bool timing);

}  // namespace chordfit::experiments
