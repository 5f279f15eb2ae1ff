// coarse_start: would a coarse-to-fine start make the closure faster without changing it?
// For each seed, the truth valve of a cohort preset (synthetic_case.h truthCaseAtEdge: the same
// anatomy, cords at their anatomical points with the truth's rest lengths and PM tips, the same
// lesion tissue) is closed on a fine mesh twice with the simulator defaults:
//   cold    from the open state, as `chordfit simulate` and every fit closure do;
//   coarse  the same valve closed on a mesh `ratio` times coarser, its closed state carried to
//           the fine mesh (each fine open vertex takes the barycentric coordinates of its
//           closest point on the coarse open mesh, applied to the coarse closed mesh), then a
//           warm-started fine closure from there (full pressure, no ramp, as a fit's finite
//           differences).
// It prints both closures' steps and times and how far apart their closed states are
// (docs/performance.md, "Coarse-to-fine start"). No files are written. Arguments are parsed
// by hand (CLI11 is confined to tools/main.cpp).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/closure_model.h"
#include "core/cohort_presets.h"
#include "core/metrics.h"
#include "core/synthetic_case.h"
#include "core/xpbd_constraints.h"
#include "experiments/tool_support.h"

namespace {

using namespace chordfit;

constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;
constexpr int kExitUsage = 2;

const char* kUsage = R"(usage: coarse_start PRESET [options]

Closes the truth valve of PRESET (chordfit make-case --list) on a fine mesh from the open
state (cold), and again warm-started from the closure of the same valve on a coarser mesh,
with the simulator defaults; prints per seed the steps and seconds of each and the distance
between the two closed states (mean and largest over the vertices, mm).

options:
  --seeds LIST   patient seeds, comma-separated (default 1,2,3)
  --edge MM      edge of the fine mesh (default 0.8, about 2,000 vertices)
  --ratio R      coarse edge / fine edge, > 1 (default 2)
)";

int usageError(const std::string& message) {
  std::cerr << "coarse_start: error: " << message << "\n(coarse_start --help)\n";
  return kExitUsage;
}

// The coarse closed state carried to the fine mesh: each fine open vertex (V_fine) is placed
// at the barycentric coordinates of its closest point on the coarse open mesh (V_coarse,
// F_coarse), taken on the coarse closed mesh (closed_coarse, same rows as V_coarse). The
// search is exhaustive, O(#V_fine #F_coarse): this is an experiment, not a solver path.
//   Returns #V_fine by 3.
Eigen::MatrixXd carryOver(const Eigen::MatrixXd& V_fine, const Eigen::MatrixXd& V_coarse,
                          const Eigen::MatrixXi& F_coarse, const Eigen::MatrixXd& closed_coarse) {
  Eigen::MatrixXd start(V_fine.rows(), 3);
  for (Eigen::Index i = 0; i < V_fine.rows(); ++i) {
    const Eigen::Vector3d p = V_fine.row(i).transpose();
    double best = std::numeric_limits<double>::infinity();
    Eigen::Index best_face = 0;
    Eigen::Vector3d best_weights = Eigen::Vector3d::Zero();
    for (Eigen::Index f = 0; f < F_coarse.rows(); ++f) {
      const Eigen::Vector3d a = V_coarse.row(F_coarse(f, 0)).transpose();
      const Eigen::Vector3d b = V_coarse.row(F_coarse(f, 1)).transpose();
      const Eigen::Vector3d c = V_coarse.row(F_coarse(f, 2)).transpose();
      double wa = 0.0, wb = 0.0, wc = 0.0;
      closestPointOnTriangle(p, a, b, c, wa, wb, wc);
      const double d2 = (p - (wa * a + wb * b + wc * c)).squaredNorm();
      if (d2 < best) {
        best = d2;
        best_face = f;
        best_weights = Eigen::Vector3d(wa, wb, wc);
      }
    }
    Eigen::RowVector3d q = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 3; ++k) q += best_weights(k) * closed_coarse.row(F_coarse(best_face, k));
    start.row(i) = q;
  }
  return start;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string closureCell(const SimulationResult& r, double seconds) {
  char text[64];
  std::snprintf(text, sizeof text, "%d%s / %.2f", r.steps, r.converged ? "" : " (cap)", seconds);
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  int exit_code = kExitOk;
  const CohortPreset* preset =
      tool_support::presetArgument(argc, argv, kUsage, usageError, exit_code);
  if (!preset) return exit_code;
  std::vector<std::uint64_t> seeds = {1, 2, 3};
  double edge = 0.8, ratio = 2.0;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--seeds") {
      std::string bad;
      if (!has_value || !tool_support::parseSeedList(argv[++i], seeds, bad)) {
        return usageError("--seeds: expected positive integers, got \"" + bad + "\"");
      }
    } else if (arg == "--edge") {
      if (!has_value || !tool_support::parseNumber(argv[++i], edge) || !(edge >= 0.3) ||
          !(edge <= 5.0)) {
        return usageError("--edge: expected a length in [0.3, 5] mm");
      }
    } else if (arg == "--ratio") {
      if (!has_value || !tool_support::parseNumber(argv[++i], ratio) || !(ratio > 1.0) ||
          !(ratio <= 4.0)) {
        return usageError("--ratio: expected a number in (1, 4]");
      }
    } else {
      return usageError("unknown argument \"" + arg + "\"");
    }
  }

  std::printf(
      "| Seed | Vertices fine / coarse | Coarse: steps / s | Warm fine: steps / s | Coarse "
      "start total s | Cold: steps / s | Speed-up | Apart: mean / max (mm) | AvgD warm / cold "
      "(mm) | Prolapse warm / cold |\n"
      "|---|---|---|---|---:|---|---:|---|---|---|\n");
  const SimulationSettings settings;  // the simulator defaults, what simulate and fit use
  for (const std::uint64_t seed : seeds) {
    SyntheticCaseOptions options;
    options.preset = preset->name;
    options.seed = seed;
    options.edge_mm = 3.0;  // only the truth's cords and anatomy are used; keep its closure cheap
    try {
      const SyntheticCase synthetic = makeSyntheticCase(options);
      const ValveCase fine = truthCaseAtEdge(synthetic, edge);
      const ValveCase coarse = truthCaseAtEdge(synthetic, edge * ratio);
      auto clock = std::chrono::steady_clock::now();
      const SimulationResult coarse_result = simulateClosure(coarse, *coarse.cords, settings);
      const double coarse_seconds = secondsSince(clock);
      if (!coarse_result.ok()) throw std::runtime_error("coarse closure: " + coarse_result.error);
      clock = std::chrono::steady_clock::now();
      const Eigen::MatrixXd start =
          carryOver(fine.mesh.V, coarse.mesh.V, coarse.mesh.F, coarse_result.V);
      const SimulationResult warm = simulateClosure(fine, *fine.cords, settings, &start);
      const double warm_seconds = secondsSince(clock);  // the carry-over included
      clock = std::chrono::steady_clock::now();
      const SimulationResult cold = simulateClosure(fine, *fine.cords, settings);
      const double cold_seconds = secondsSince(clock);
      if (!warm.ok() || !cold.ok()) throw std::runtime_error(warm.ok() ? cold.error : warm.error);
      const Eigen::VectorXd apart = (warm.V - cold.V).rowwise().norm();
      const ValveMetrics mw = computeMetrics(fine, warm.V), mc = computeMetrics(fine, cold.V);
      const double total = coarse_seconds + warm_seconds;
      std::printf(
          "| %llu | %ld / %ld | %s | %s | %.2f | %s | %.1f× | %.3f / %.3f | %.3f / %.3f | %s / %s "
          "|\n",
          static_cast<unsigned long long>(seed), static_cast<long>(fine.mesh.V.rows()),
          static_cast<long>(coarse.mesh.V.rows()),
          closureCell(coarse_result, coarse_seconds).c_str(),
          closureCell(warm, warm_seconds).c_str(), total, closureCell(cold, cold_seconds).c_str(),
          cold_seconds / total, apart.mean(), apart.maxCoeff(), mw.deviation.mean,
          mc.deviation.mean, tool_support::joinedNames(mw.mesh_prolapse.segments).c_str(),
          tool_support::joinedNames(mc.mesh_prolapse.segments).c_str());
      std::fflush(stdout);
    } catch (const std::exception& e) {
      std::cerr << "coarse_start: " << preset->name << " seed " << seed << ": " << e.what() << "\n";
      return kExitFailed;
    }
  }
  return kExitOk;
}
