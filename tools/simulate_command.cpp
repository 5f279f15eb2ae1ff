#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>

#include "core/atomic_file.h"
#include "core/case_io.h"
#include "core/closure_model.h"
#include "core/enface_figure.h"
#include "core/mesh_io.h"
#include "core/metrics.h"
#include "core/metrics_json.h"
#include "core/section_figure.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

namespace {

using Clock = std::chrono::steady_clock;

// Tracing information only means something near a tracing plane: farther than this from
// every plane a vertex gets no "distance to the nearest tracing point" (NaN).
constexpr double kTracingPlaneReachMm = 3.0;

Eigen::VectorXd distanceToNearestTracingPoint(const ValveCase& c, const Eigen::MatrixXd& V) {
  Eigen::VectorXd d = Eigen::VectorXd::Constant(V.rows(), std::numeric_limits<double>::quiet_NaN());
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Eigen::Vector3d p = V.row(v).transpose();
    double best = std::numeric_limits<double>::infinity();
    bool near_plane = false;
    for (const Tracing& t : c.tracings) {
      near_plane |= std::abs(t.plane_normal.dot(p - t.plane_origin)) <= kTracingPlaneReachMm;
      best = std::min(best, (t.points.rowwise() - p.transpose()).rowwise().norm().minCoeff());
    }
    if (near_plane) d(v) = best;
  }
  return d;
}

// Per-vertex scalars for ParaView / Slicer: heights above the closed annulus (plain plane and
// the prolapse reference of metrics.h) and the distance to the tracings.
std::vector<VertexScalarField> closedStateScalars(const ValveCase& c, const Eigen::MatrixXd& V) {
  const ClosedAnnulus annulus = closedAnnulus(c);
  Eigen::VectorXd plane_height(V.rows());
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    plane_height(v) = annulus.frame.plane.signedDistance(V.row(v).transpose());
  }
  return {{"height_above_annulus_plane_mm", plane_height},
          {"prolapse_height_mm", heightAboveAnnulus(annulus.frame, annulus.ring, V)},
          {"distance_to_tracing_mm", distanceToNearestTracingPoint(c, V)}};
}

// Progress lines on stderr, at most one per half second, once the run has taken a second.
SimulationSettings withProgress(SimulationSettings settings, const std::string& label, bool quiet) {
  if (quiet) return settings;
  const auto start = Clock::now();
  auto last = std::make_shared<Clock::time_point>(start);
  settings.progress_every = 50;
  // With the pressure ramp's end and the quasi-static tolerance, so that a reader can tell
  // how far the run has to go: loading until the ramp ends, then settling until the largest
  // step stays below the tolerance (simulation_settings.h).
  const double ramp_ms = settings.ramp_ms, tolerance_mm = settings.tolerance_mm;
  settings.progress = [start, last, label, ramp_ms, tolerance_mm](const SimulationProgress& p) {
    const auto now = Clock::now();
    if (now - start < std::chrono::seconds(1) || now - *last < std::chrono::milliseconds(500)) {
      return;
    }
    *last = now;
    std::fprintf(stderr,
                 "  %s: step %6d  t = %8.2f ms (%s)  max step %.2e mm (settles below %.0e)  "
                 "contacts %d  (%.1f s)\n",
                 label.c_str(), p.step, p.time_ms, p.time_ms < ramp_ms ? "loading" : "settling",
                 p.max_displacement_mm, tolerance_mm, p.contacts,
                 std::chrono::duration<double>(now - start).count());
  };
  return settings;
}

void writeState(const std::filesystem::path& dir, const std::string& stem, const ValveCase& c,
                const Eigen::MatrixXd& V) {
  const auto scalars = closedStateScalars(c, V);
  writePly(dir / (stem + ".ply"), V, c.mesh.F, scalars);
  writeVtk(dir / (stem + ".vtk"), V, c.mesh.F, scalars);
}

// The opened state's files (writeState "opened"), written with --phase open only.
std::vector<std::string> openedStateFiles() { return {"opened.ply", "opened.vtk"}; }

}  // namespace

int runSimulate(const SimulateOptions& options) {
  if (options.phase != "close" && options.phase != "open") {
    std::cerr << "error: simulate: --phase: expected close or open, got \"" << options.phase
              << "\"\n";
    return kExitBadInput;
  }
  auto loaded =
      loadCaseWithCords("simulate", options.case_dir, options.tissue_file, options.cords_file);
  if (!loaded) return kExitBadInput;
  ValveCase& valve_case = loaded->valve_case;
  const CordSet& cords = loaded->cords;
  auto case_settings =
      caseSettingsOrReport(valve_case, options.case_dir, SettingsUse::kClose, "simulate",
                           options.settings_overrides, options.tissue_file);
  if (!case_settings) return kExitBadInput;
  SimulationSettings& settings = *case_settings;
  settings.threads = options.threads;

  const SimulationResult closed =
      simulateClosure(valve_case, cords, withProgress(settings, "close", options.quiet));
  if (!closed.ok()) return reportClosureFailure(closed, options.case_dir);
  SimulationResult opened;
  if (options.phase == "open") {
    settings.phase = ClosurePhase::kOpen;
    opened = simulateClosure(valve_case, cords, withProgress(settings, "open", options.quiet),
                             &closed.V);
    if (!opened.ok()) return reportClosureFailure(opened, options.case_dir);
  }

  const ValveMetrics metrics = computeMetrics(valve_case, closed.V);
  nlohmann::json j = metricsJson(metrics);
  j["converged"] = closed.converged;
  j["steps"] = closed.steps;
  j["averaged_steps"] = closed.averaged_steps;
  j["dt_ms"] = closed.dt_ms;
  j["edge_contact"] = closed.edge_contact;
  j["sim_seconds"] = closed.seconds;
  j["threads"] = options.threads;
  j["threads_gave_up"] = closed.threads_gave_up;
  j["cords"] = cords.cords.size();
  if (!options.settings_overrides.empty()) j["settings_overrides"] = options.settings_overrides;
  // How far the opening went back: the opened and the closed valve's mean distance from the
  // case's open state (the first alone has no scale).
  const double opened_distance_mm =
      options.phase == "open" ? (opened.V - valve_case.mesh.V).rowwise().norm().mean() : 0.0;
  const double closed_distance_mm = (closed.V - valve_case.mesh.V).rowwise().norm().mean();
  if (options.phase == "open") {
    j["open_phase"] = {{"converged", opened.converged},
                       {"steps", opened.steps},
                       {"sim_seconds", opened.seconds},
                       {"mean_distance_to_open_state_mm", opened_distance_mm},
                       {"closed_mean_distance_to_open_state_mm", closed_distance_mm}};
  }
  // A closure alone supersedes the opened state of an earlier --phase open.
  StagedOutput staged(options.out_dir, simulateOutputFiles(options),
                      options.phase == "open" ? std::vector<std::string>{} : openedStateFiles(),
                      "simulate");
  const std::filesystem::path& out = staged.dir();
  writeState(out, "closed", valve_case, closed.V);
  if (options.phase == "open") writeState(out, "opened", valve_case, opened.V);
  writeFileAtomically(out / "metrics.json", j.dump(2) + "\n");
  std::string sections;
  if (options.sections) {
    sections = caseSectionFigureSvg(
        valve_case, {{"simulated closed", closed.V, "", false, 2.0}},
        {valve_case.name + ": simulated closed valve and tracings, one panel per tracing plane"});
  }
  if (!sections.empty()) writeFileAtomically(out / "sections.svg", sections);
  writeFileAtomically(out / "enface.svg",
                      enfaceFigureSvg(valve_case, closed.V, valve_case.name, metrics));
  const StagedOutput::Published published = staged.publish();

  std::printf("closure: %s after %d steps, %.2f s%s%s\n",
              closed.converged ? "converged" : "NOT converged (step cap reached)", closed.steps,
              closed.seconds, closed.edge_contact ? " (edge midpoints as contact points too)" : "",
              closed.averaged_steps > 0 ? (": result = mean of the last " +
                                           std::to_string(closed.averaged_steps) + " steps")
                                              .c_str()
                                        : "");
  if (options.phase == "open") {
    std::printf(
        "opening: %s after %d steps, %.2f s; the opened valve lies %.2f mm from the open state "
        "on average, the closed one %.2f mm (%.0f %% of the way back)\n",
        opened.converged ? "converged" : "NOT converged", opened.steps, opened.seconds,
        opened_distance_mm, closed_distance_mm,
        closed_distance_mm > 0.0 ? 100.0 * (1.0 - opened_distance_mm / closed_distance_mm) : 0.0);
  }
  std::cout << table1Header() << table1Row(valve_case.name, metrics);
  std::cout << closedValveSummary(metrics);
  if (options.report_files) std::cout << wroteLine(options.out_dir, published) << "\n";
  return kExitOk;
}

std::vector<std::string> closureOutputFiles(bool open_phase) {
  std::vector<std::string> files = {"closed.ply", "closed.vtk"};
  if (open_phase) {
    const std::vector<std::string> opened = openedStateFiles();
    files.insert(files.end(), opened.begin(), opened.end());
  }
  files.insert(files.end(), {"metrics.json", "enface.svg"});
  return files;
}

std::vector<std::string> simulateOutputFiles(const SimulateOptions& options) {
  std::vector<std::string> files = closureOutputFiles(options.phase == "open");
  if (options.sections) files.push_back("sections.svg");
  return files;
}

}  // namespace chordfit::cli
