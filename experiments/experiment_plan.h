// The benchmark experiments (issue "Benchmark experiments") as a fixed list of cases and jobs.
// A case is one `chordfit make-case` run (preset, patient seed, tracing variant); a job is one
// method on one case (heuristic closure, truth closure, or a `chordfit fit`). The plan is a
// pure function of the configuration, so every process of a sharded run sees the same list
// in the same order and picks its own share by index.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace chordfit::experiments {

struct CaseSpec {
  std::string id;  // directory name, e.g. "prolapse-P2_s1" or "prolapse-P2_s1_noise0.6"
  std::string preset;
  int seed = 1;
  int planes = 6;
  double noise_mm = 0.3;
  double dropout = 0.1;
  double edge_mm = 2.5;
};

enum class Method { kHeuristic, kTruth, kFit };

struct JobSpec {
  std::string id;  // "<case id>__<method tag>", a file name
  std::string case_id;
  Method method = Method::kHeuristic;
  std::string params;          // fit only: groups | scales | scales+tips
  std::string optimizer;       // fit only: ceres | bobyqa | cobyla | sbplx | crs2
  std::string label;           // Table 1 row label: heuristic, manual-like, per-cord, ...
  bool tissue_prefit = false;  // fit only: `fit --tissue-prefit` (docs/fitting.md)
};

struct ExperimentConfig {
  std::vector<std::string> presets;
  std::vector<int> seeds;
  double edge_mm = 2.5;
  int planes = 6;
  double noise_mm = 0.3;
  double dropout = 0.1;
  int max_sims = 300;  // forward-simulation budget of every fit (equal for all optimisers)
  int fit_threads = 2;
  // Scale bounds of every fit (`fit --scale-bounds`); unset: the fit's default [0.7, 1.5].
  std::optional<std::pair<double, double>> scale_bounds;
  // Finite-difference perturbations warm-start from the base closed state (`fit --fd-warm`):
  // about 10x cheaper per Jacobian; the reported value is still a full closure.
  bool fd_warm = true;
  // Optimiser comparison: these presets at the first seed, per-cord scales.
  std::vector<std::string> optimizer_presets;
  std::vector<std::string> optimizers;
  // Sensitivity sweeps on this preset at the first seed: heuristic and per-cord fit.
  std::string sensitivity_preset;
  std::vector<double> noise_sweep;
  std::vector<int> plane_sweep;
};

// Full run (the default): every cohort preset, seeds 1-3, all optimisers, both sweeps.
ExperimentConfig fullConfig();
// Reduced run: every preset at seed 1, the optimiser comparison on prolapse-P2 only, both
// sweeps (61 of the full plan's 161 jobs).
ExperimentConfig reducedConfig();
// CI smoke run: one case (normal-1 seed 2, edge 3 mm, 3 planes: the bundled small-normal),
// small fit budget, every method and table kind but no extra sweep cases.
ExperimentConfig smokeConfig();

struct ExperimentPlan {
  std::vector<CaseSpec> cases;
  std::vector<JobSpec> jobs;
};

// Cases and jobs in a fixed order (cases: preset, seed, then sweep variants; jobs grouped by
// case). A job shared by several experiments (the per-cord Ceres fit is Table 1, optimiser
// comparison and sensitivity baseline at once) appears once.
ExperimentPlan makePlan(const ExperimentConfig& config);

const CaseSpec& findCase(const ExperimentPlan& plan, const std::string& case_id);

// The id of a preset's case at a seed with the plan's default options ("prolapse-P2_s1"); the
// sweep variants add a suffix to it.
std::string baseCaseId(const std::string& preset, int seed);

// The options that change a plan's numbers but not its job ids, where `config` differs from the
// plan's `defaults`: "--edge 2 --max-sims 150 --scale-bounds 0.6,1.5" (each only when it
// differs; "" for the defaults). The budget and bounds are the fits' own: a plan without a fit
// job (`--methods heuristic,truth`) leaves them out, as its numbers do not depend on them.
std::string nonDefaultOptions(const ExperimentConfig& config, const ExperimentConfig& defaults,
                              const ExperimentPlan& plan);

// What identifies a plan's jobs whatever options chose them: 16 hex digits of the FNV-1a hash of
// its sorted job ids ("--seeds 1,2,3" and no --seeds give the same plan id), and of
// `option_values` (nonDefaultOptions) when not empty, so that a plan run with another budget,
// edge or scale bounds has another id while the defaults keep the id they always had.
std::string planId(const ExperimentPlan& plan, const std::string& option_values = "");

// "i/N" with 1 <= i <= N. Returns false on malformed text.
struct Shard {
  int index = 1;  // 1-based
  int count = 1;
};
bool parseShard(const std::string& text, Shard& shard);
// Round-robin: item k (0-based, plan order) belongs to shard (k mod N) + 1.
bool inShard(std::size_t item, const Shard& shard);

// Table 1 labels of the methods, in table order.
std::string methodTag(const JobSpec& job);  // "heuristic", "truth", "fit_scales_ceres", ...

}  // namespace chordfit::experiments
