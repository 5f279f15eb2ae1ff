// mesh_convergence: how the closed valve of a cohort truth changes with the mesh resolution.
// For each seed, the truth is made on a fine reference mesh with noise-free, gap-free
// tracings; then the same physical valve (anatomy, cords at their anatomical points with the
// truth's rest lengths and PM tips, lesion tissue; synthetic_case.h truthCaseAtEdge) is closed
// on coarser meshes and measured against the reference's tracings. So the mean deviation of a
// row is the discretisation error as the tracings see it: what a fit on a case mesh of that
// edge cannot get below even with the true cords (docs/performance.md, "Mesh convergence").
// No files are written. Arguments are parsed by hand (CLI11 is confined to tools/main.cpp).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "core/closure_model.h"
#include "core/cohort_presets.h"
#include "core/metrics.h"
#include "core/synthetic_case.h"
#include "experiments/tool_support.h"

namespace {

using namespace chordfit;

constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;
constexpr int kExitUsage = 2;

const char* kUsage = R"(usage: mesh_convergence PRESET [options]

Closes the truth of PRESET (chordfit make-case --list) on a fine reference mesh and the same
valve on coarser meshes, and prints per seed and edge: vertices, convergence, the deviation
from the reference's noise-free tracings (mean, max), the mesh prolapse and the orifice
coverage. The deviation is the discretisation error a fit on that mesh cannot go below.

options:
  --seeds LIST       patient seeds, comma-separated (default 1,2,3)
  --edges LIST       mesh edges to compare, mm (default 3,2.5,2,1.5,1.25,1)
  --reference MM     edge of the reference mesh (default 0.6)
  --fit-settings     close the coarser meshes with the simulator defaults (what a fit uses)
                     instead of the truth's tighter settings
)";

int usageError(const std::string& message) {
  std::cerr << "mesh_convergence: error: " << message << "\n(mesh_convergence --help)\n";
  return kExitUsage;
}

void printRow(std::uint64_t seed, double edge, const ValveCase& valve_case,
              const SimulationResult& result, double seconds) {
  const ValveMetrics m = computeMetrics(valve_case, result.V);
  std::printf("| %llu | %.2f | %ld | %s (%d) | %.3f | %.2f | %s | %.2f | %.1f %% | %.1f |\n",
              static_cast<unsigned long long>(seed), edge,
              static_cast<long>(valve_case.mesh.V.rows()), result.converged ? "yes" : "no",
              result.steps, m.deviation.mean, m.deviation.max,
              tool_support::joinedNames(m.mesh_prolapse.segments).c_str(),
              m.mesh_prolapse.max_height_mm, 100.0 * m.orifice.coverage(), seconds);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  int exit_code = kExitOk;
  const CohortPreset* preset =
      tool_support::presetArgument(argc, argv, kUsage, usageError, exit_code);
  if (!preset) return exit_code;
  std::vector<std::uint64_t> seeds = {1, 2, 3};
  std::vector<double> edges = {3.0, 2.5, 2.0, 1.5, 1.25, 1.0};
  double reference_edge = 0.6;
  bool fit_settings = false;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    std::string bad;
    if (arg == "--seeds") {
      if (!has_value || !tool_support::parseSeedList(argv[++i], seeds, bad)) {
        return usageError("--seeds: expected positive integers, got \"" + bad + "\"");
      }
    } else if (arg == "--edges") {
      if (!has_value || !tool_support::parseLengthList(argv[++i], edges, bad)) {
        return usageError("--edges: expected positive lengths in mm, got \"" + bad + "\"");
      }
    } else if (arg == "--reference") {
      if (!has_value || !tool_support::parseNumber(argv[++i], reference_edge) ||
          !(reference_edge > 0.0)) {
        return usageError("--reference: expected a positive length in mm");
      }
    } else if (arg == "--fit-settings") {
      fit_settings = true;
    } else {
      return usageError("unknown argument \"" + arg + "\"");
    }
  }
  for (const double edge : edges) {
    if (edge <= reference_edge) {
      char text[96];
      std::snprintf(text, sizeof text, "--edges: %g mm is not coarser than the reference (%g mm)",
                    edge, reference_edge);
      return usageError(text);
    }
  }
  std::printf(
      "| Seed | Edge (mm) | Vertices | Converged (steps) | Mean to reference tracings (mm) | Max "
      "(mm) | Mesh prolapse | Highest point (mm) | Orifice covered | Time (s) |\n"
      "|---|---:|---:|---|---:|---:|---|---:|---:|---:|\n");
  for (const std::uint64_t seed : seeds) {
    SyntheticCaseOptions options;
    options.preset = preset->name;
    options.seed = seed;
    options.edge_mm = reference_edge;
    options.truth_edge_ratio = 1.0;  // the reference is the truth mesh itself
    // Point insertions as in the cohort and in the study of docs/performance.md ("Mesh
    // convergence"), also for references finer than 0.75 mm, where make-case spreads them.
    options.truth_settings = truthSimulationSettings();
    options.tracing.noise_mm = 0.0;
    options.tracing.dropout_fraction = 0.0;
    try {
      const SyntheticCase reference = makeSyntheticCase(options);
      printRow(seed, reference_edge, reference.truth_case, reference.truth_result,
               reference.seconds);
      const SimulationSettings settings =
          fit_settings ? SimulationSettings{} : reference.truth_settings;
      for (const double edge : edges) {
        const auto start = std::chrono::steady_clock::now();
        const ValveCase coarse = truthCaseAtEdge(reference, edge);
        const SimulationResult result = simulateClosure(coarse, *coarse.cords, settings);
        if (!result.ok()) {
          std::printf("| %llu | %.2f | %ld | failed: %s | | | | | | |\n",
                      static_cast<unsigned long long>(seed), edge,
                      static_cast<long>(coarse.mesh.V.rows()), result.error.c_str());
          continue;
        }
        printRow(seed, edge, coarse, result,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      }
    } catch (const std::exception& e) {
      std::cerr << "mesh_convergence: " << preset->name << " seed " << seed << ": " << e.what()
                << "\n";
      return kExitFailed;
    }
  }
  return kExitOk;
}
