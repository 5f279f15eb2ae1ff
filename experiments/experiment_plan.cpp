#include "experiments/experiment_plan.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <set>
#include <stdexcept>
#include <vector>

#include "core/cohort_presets.h"

namespace chordfit::experiments {

namespace {

// Short decimal for ids: 0.6 -> "0.6", 1 -> "1".
std::string shortNumber(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

CaseSpec baseCase(const ExperimentConfig& c, const std::string& preset, int seed) {
  CaseSpec s;
  s.preset = preset;
  s.seed = seed;
  s.planes = c.planes;
  s.noise_mm = c.noise_mm;
  s.dropout = c.dropout;
  s.edge_mm = c.edge_mm;
  s.id = baseCaseId(preset, seed);
  return s;
}

JobSpec fitJob(const std::string& case_id, const std::string& params, const std::string& optimizer,
               const std::string& label, bool tissue_prefit = false) {
  JobSpec j;
  j.tissue_prefit = tissue_prefit;
  j.case_id = case_id;
  j.method = Method::kFit;
  j.params = params;
  j.optimizer = optimizer;
  j.label = label;
  return j;
}

JobSpec simpleJob(const std::string& case_id, Method method) {
  JobSpec j;
  j.case_id = case_id;
  j.method = method;
  j.label = method == Method::kTruth ? "truth" : "heuristic";
  return j;
}

}  // namespace

ExperimentConfig fullConfig() {
  ExperimentConfig c;
  for (const CohortPreset& p : cohortPresets()) {
    c.presets.push_back(p.name);
    if (!p.intended_prolapse.empty()) c.optimizer_presets.push_back(p.name);
  }
  c.seeds = {1, 2, 3};
  c.optimizers = {"ceres", "bobyqa", "cobyla", "sbplx", "crs2"};
  c.sensitivity_preset = "prolapse-P2";
  c.noise_sweep = {0.0, 0.3, 0.6, 1.0};
  c.plane_sweep = {3, 6, 12};
  return c;
}

ExperimentConfig reducedConfig() {
  ExperimentConfig c = fullConfig();
  c.seeds = {1};
  c.optimizer_presets = {"prolapse-P2"};
  return c;
}

ExperimentConfig smokeConfig() {
  ExperimentConfig c;
  // The parameters of the bundled test case build/cases/small-normal (cases/CMakeLists.txt),
  // so a smoke run can take it with --case-source instead of generating it.
  c.presets = {"normal-1"};
  c.seeds = {2};
  c.edge_mm = 3.0;
  c.planes = 3;
  // The pre-fits (about 38 closures on this case) and one Jacobian and step of every Ceres
  // method, so that the smoke run takes an optimiser step in each (16 left every method at
  // the pre-fit's result, and its tables showed four identical rows).
  c.max_sims = 80;
  c.optimizer_presets = {"normal-1"};
  c.optimizers = {"ceres", "bobyqa"};
  c.sensitivity_preset = "normal-1";
  c.noise_sweep = {c.noise_mm};
  c.plane_sweep = {c.planes};
  return c;
}

std::string methodTag(const JobSpec& job) {
  switch (job.method) {
    case Method::kHeuristic:
      return "heuristic";
    case Method::kTruth:
      return "truth";
    case Method::kFit:
      break;
  }
  std::string params = job.params;
  for (char& ch : params) {
    if (ch == '+') ch = '-';
  }
  // "-tissue" inside the params part, so that the optimisers of the per-cord fit
  // (`--methods 'fit_scales_*'`) do not take the tissue jobs with them.
  if (job.tissue_prefit) params += "-tissue";
  return "fit_" + params + "_" + job.optimizer;
}

ExperimentPlan makePlan(const ExperimentConfig& config) {
  if (config.seeds.empty() || config.presets.empty()) {
    throw std::invalid_argument("experiment plan: no presets or no seeds");
  }
  ExperimentPlan plan;
  std::set<std::string> job_ids;
  auto addJob = [&](JobSpec job) {
    job.id = job.case_id + "__" + methodTag(job);
    if (job_ids.insert(job.id).second) plan.jobs.push_back(job);
  };
  const int first_seed = config.seeds.front();

  // Table 1: every preset and seed, the five methods of the issue and the opt-in tissue pre-fit.
  for (const std::string& preset : config.presets) {
    for (int seed : config.seeds) {
      const CaseSpec c = baseCase(config, preset, seed);
      plan.cases.push_back(c);
      addJob(simpleJob(c.id, Method::kHeuristic));
      addJob(fitJob(c.id, "groups", "ceres", "manual-like"));
      addJob(fitJob(c.id, "scales", "ceres", "per-cord"));
      addJob(fitJob(c.id, "scales+tips", "ceres", "per-cord+tips"));
      addJob(fitJob(c.id, "scales", "ceres", "per-cord+tissue", true));
      addJob(simpleJob(c.id, Method::kTruth));
    }
  }
  // Optimiser comparison: per-cord scales, equal budget.
  for (const std::string& preset : config.optimizer_presets) {
    const std::string case_id = baseCase(config, preset, first_seed).id;
    for (const std::string& optimizer : config.optimizers) {
      addJob(fitJob(case_id, "scales", optimizer, "per-cord " + optimizer));
    }
  }
  // Sensitivity: one preset, tracing noise and plane count varied one at a time.
  if (!config.sensitivity_preset.empty()) {
    std::vector<CaseSpec> variants;
    for (double noise : config.noise_sweep) {
      CaseSpec c = baseCase(config, config.sensitivity_preset, first_seed);
      if (noise != config.noise_mm) {
        c.noise_mm = noise;
        c.id += "_noise" + shortNumber(noise);
      }
      variants.push_back(c);
    }
    for (int planes : config.plane_sweep) {
      CaseSpec c = baseCase(config, config.sensitivity_preset, first_seed);
      if (planes != config.planes) {
        c.planes = planes;
        c.id += "_planes" + std::to_string(planes);
      }
      variants.push_back(c);
    }
    for (const CaseSpec& c : variants) {
      bool known = false;
      for (const CaseSpec& k : plan.cases) known |= k.id == c.id;
      if (!known) plan.cases.push_back(c);
      addJob(simpleJob(c.id, Method::kHeuristic));
      addJob(fitJob(c.id, "scales", "ceres", "per-cord"));
      addJob(simpleJob(c.id, Method::kTruth));
    }
  }
  return plan;
}

std::string baseCaseId(const std::string& preset, int seed) {
  return preset + "_s" + std::to_string(seed);
}

std::string nonDefaultOptions(const ExperimentConfig& config, const ExperimentConfig& defaults,
                              const ExperimentPlan& plan) {
  const bool fits = std::any_of(plan.jobs.begin(), plan.jobs.end(),
                                [](const JobSpec& job) { return job.method == Method::kFit; });
  std::string text;
  auto add = [&](const std::string& option) { text += (text.empty() ? "" : " ") + option; };
  if (config.edge_mm != defaults.edge_mm) add("--edge " + shortNumber(config.edge_mm));
  if (fits && config.max_sims != defaults.max_sims)
    add("--max-sims " + std::to_string(config.max_sims));
  if (fits && config.scale_bounds && config.scale_bounds != defaults.scale_bounds) {
    add("--scale-bounds " + shortNumber(config.scale_bounds->first) + "," +
        shortNumber(config.scale_bounds->second));
  }
  return text;
}

std::string planId(const ExperimentPlan& plan, const std::string& option_values) {
  std::vector<std::string> ids;
  for (const JobSpec& job : plan.jobs) ids.push_back(job.id);
  std::sort(ids.begin(), ids.end());
  // After the ids, so that the default options hash exactly as before they were part of it.
  if (!option_values.empty()) ids.push_back("options " + option_values);
  std::uint64_t hash = 14695981039346656037ull;  // FNV-1a, 64 bit
  for (const std::string& id : ids) {
    for (const char c : id + "\n") {
      hash ^= static_cast<unsigned char>(c);
      hash *= 1099511628211ull;
    }
  }
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

const CaseSpec& findCase(const ExperimentPlan& plan, const std::string& case_id) {
  for (const CaseSpec& c : plan.cases) {
    if (c.id == case_id) return c;
  }
  throw std::logic_error("experiment plan: no case " + case_id);
}

bool parseShard(const std::string& text, Shard& shard) {
  int index = 0, count = 0;
  char slash = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &index, &slash, &count, &extra) != 3 || slash != '/') {
    return false;
  }
  if (count < 1 || index < 1 || index > count) return false;
  shard = {index, count};
  return true;
}

bool inShard(std::size_t item, const Shard& shard) {
  return static_cast<int>(item % static_cast<std::size_t>(shard.count)) == shard.index - 1;
}

}  // namespace chordfit::experiments
