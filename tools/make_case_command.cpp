// chordfit make-case: a synthetic case with known truth (core/synthetic_case.h).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "core/metrics.h"
#include "core/synthetic_case.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

namespace {

using Clock = std::chrono::steady_clock;

int listPresets() {
  for (const CohortPreset& p : cohortPresets()) {
    std::printf("%-12s %s; prolapse: %s\n", p.name.c_str(), p.summary.c_str(),
                joinSegments(p.intended_prolapse).c_str());
  }
  return kExitOk;
}

// Stage lines at once, simulator lines at most every half second once a run took a second.
void attachProgress(SyntheticCaseOptions& options) {
  const auto start = Clock::now();
  options.message = [start](const std::string& text) {
    std::fprintf(stderr, "make-case: %s (%.1f s)\n", text.c_str(),
                 std::chrono::duration<double>(Clock::now() - start).count());
  };
  auto sim_start = std::make_shared<Clock::time_point>();
  auto last = std::make_shared<Clock::time_point>();
  options.simulation_progress = [sim_start, last](const SimulationProgress& p) {
    const auto now = Clock::now();
    if (p.step <= 50) *sim_start = *last = now;
    if (now - *sim_start < std::chrono::seconds(1) ||
        now - *last < std::chrono::milliseconds(500)) {
      return;
    }
    *last = now;
    std::fprintf(stderr,
                 "  truth: step %6d  t = %8.2f ms  max step %.2e mm  contacts %d  (%.1f s)\n",
                 p.step, p.time_ms, p.max_displacement_mm, p.contacts,
                 std::chrono::duration<double>(now - *sim_start).count());
  };
}

}  // namespace

int runMakeCase(const MakeCaseOptions& options) {
  if (options.list) return listPresets();
  if (options.preset.empty()) {
    std::cerr << "error: make-case: --preset: required (one of: " << cohortPresetNames()
              << "; see make-case --list)\n";
    return kExitBadInput;
  }
  if (findCohortPreset(options.preset) == nullptr) {
    std::cerr << "error: make-case: --preset: unknown preset \"" << options.preset
              << "\" (known: " << cohortPresetNames() << ")\n";
    return kExitBadInput;
  }
  if (options.out_dir.empty()) {
    std::cerr << "error: make-case: --out: required\n";
    return kExitBadInput;
  }
  // The library takes edges down to 0.5 mm (mesh_convergence's references), but no truth
  // finer than 0.5 mm has been seen to close: --edge 0.5 (truth 0.25 mm, 18,504 vertices,
  // point insertions) diverged three times, the last with the step quartered, after ~10
  // minutes (2026-11-27), and the insertion patch such fine truths now get was not tried
  // there. --edge 1 settles (truth 0.5 mm, 2,648 steps). docs/performance.md, "Fine meshes".
  // So the command's range is [1, 5] mm, stated as such: the library's [0.5, 5] named a
  // range whose lower half was then refused.
  if (!(std::isfinite(options.edge_mm) && options.edge_mm >= kMinCaseEdgeMm &&
        options.edge_mm <= kMaxCaseEdgeMm)) {
    std::cerr << "error: make-case: --edge: must be in [" << kMinCaseEdgeMm << ", "
              << kMaxCaseEdgeMm << "] mm, got " << options.edge_mm;
    if (options.edge_mm >= 0.5 && options.edge_mm < 1.0)
      std::cerr << " (it gives a truth mesh finer than 0.5 mm, which has not been seen to "
                   "close: --edge 0.5 diverged)";
    std::cerr << "\n";
    return kExitBadInput;
  }

  SyntheticCaseOptions o;
  o.preset = options.preset;
  o.seed = options.seed;
  o.edge_mm = options.edge_mm;
  o.threads = options.threads;
  o.attach_at_vertices = options.attach_at_vertices;
  o.tracing.planes = options.planes;
  o.tracing.noise_mm = options.noise_mm;
  o.tracing.dropout_fraction = options.dropout;
  if (!options.quiet) attachProgress(o);

  SyntheticCase synthetic;
  try {
    synthetic = makeSyntheticCase(o);
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: make-case: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::runtime_error& e) {
    std::cerr << "error: " << options.preset << ": " << e.what() << "\n";
    return kExitSimulationFailed;
  }
  // Staged: all or nothing, and an earlier run's files this one does not write (a lesion
  // preset's truth/case/tissue.json, import-mesh's pm_tips.json) go.
  StagedOutput staged(options.out_dir, makeCaseOutputFiles(), {}, kCaseWriter);
  writeSyntheticCase(staged.dir(), synthetic);
  const StagedOutput::Published published = staged.publish();

  const ProlapseResult& prolapse = synthetic.truth_metrics.mesh_prolapse;
  const bool as_intended = prolapse.segments == synthetic.preset.intended_prolapse;
  if (!synthetic.truth_result.converged) {
    // Known at the default edge (docs/status.md, "Closures reach the quasi-static criterion"):
    // say what the truth is then and where every preset's truth settles.
    printWarning(
        "the truth closure did not reach equilibrium within %d steps; the truth is the mean of "
        "its last steps (cycling by hundredths of a mm at the most loaded cords, as five of the "
        "seven seed-1 truths do at the default edge); at --edge 2.5, the benchmark's, all its "
        "truths (seeds 1-3) settle\n",
        synthetic.truth_settings.max_steps);
  }
  if (!as_intended) {
    printWarning("the truth prolapses in %s, the preset intends %s\n",
                 joinSegments(prolapse.segments).c_str(),
                 joinSegments(synthetic.preset.intended_prolapse).c_str());
  }
  const std::vector<std::string>& traced = synthetic.truth_metrics.tracing_prolapse.segments;
  if (traced != synthetic.preset.intended_prolapse) {
    printWarning("the tracings show prolapse in %s, the preset intends %s\n",
                 joinSegments(traced).c_str(),
                 joinSegments(synthetic.preset.intended_prolapse).c_str());
  }
  int points = 0;
  for (const Tracing& t : synthetic.valve_case.tracings)
    points += static_cast<int>(t.points.rows());
  std::printf(
      "case %s (%s, seed %llu): %d vertices, %zu cords, %zu tracings (%d points) on %d "
      "planes\n",
      synthetic.valve_case.name.c_str(), synthetic.preset.name.c_str(),
      static_cast<unsigned long long>(options.seed),
      static_cast<int>(synthetic.valve_case.mesh.V.rows()),
      synthetic.valve_case.cords->cords.size(), synthetic.valve_case.tracings.size(), points,
      options.planes);
  std::printf("truth: %d vertices, closure %s in %d steps (%.1f s); prolapse %s (intended %s)\n",
              static_cast<int>(synthetic.truth_case.mesh.V.rows()),
              synthetic.truth_result.converged ? "converged" : "NOT converged",
              synthetic.truth_result.steps, synthetic.truth_result.seconds,
              joinSegments(prolapse.segments).c_str(),
              joinSegments(synthetic.preset.intended_prolapse).c_str());
  std::cout << "noise floor (true closed mesh vs tracings):\n"
            << table1Header()
            << table1Row(synthetic.valve_case.name + " truth", synthetic.truth_metrics);
  std::printf("wrote %s (case) and %s (%.1f s)%s\n", options.out_dir.c_str(),
              (std::filesystem::path(options.out_dir) / "truth").c_str(), synthetic.seconds,
              removedNote(published).c_str());
  return kExitOk;
}

std::vector<std::string> makeCaseOutputFiles() { return syntheticCaseFileNames(); }

bool isPresetName(const std::string& word) { return findCohortPreset(word) != nullptr; }

}  // namespace chordfit::cli
