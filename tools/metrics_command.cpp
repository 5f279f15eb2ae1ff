#include <cstdio>
#include <iostream>

#include "core/atomic_file.h"
#include "core/case_extent.h"
#include "core/mesh_checks.h"
#include "core/mesh_io.h"
#include "core/metrics.h"
#include "core/metrics_json.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

int runMetrics(const MetricsOptions& options) {
  auto valve_case = loadCaseOrReport(options.case_dir);
  if (!valve_case) return kExitBadInput;
  // The settings give the leaflets' thickness for the orifice coverage: a bad block is refused
  // here as by the commands that simulate.
  // --set: the settings the mesh was closed with, as simulate took them.
  if (!caseSettingsOrReport(*valve_case, options.case_dir, SettingsUse::kMeasure, "metrics",
                            options.settings_overrides))
    return kExitBadInput;
  Diagnostics diagnostics;
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  // Triangle areas are judged against the mesh's size, so one vertex thrown far away made every
  // real triangle "degenerate" (248 errors on faces without it): the areas are checked only
  // after the vertices are known to lie near the valve.
  if (!readMesh(options.mesh_file, V, F, diagnostics, options.mesh_file) ||
      !checkMesh(V, F, options.mesh_file, diagnostics, /*check_areas=*/false)) {
    return reportProblems(diagnostics);
  }
  // Metrics need the case's leaflet labels and annulus ring: same vertices, same triangles.
  const Eigen::MatrixXi& case_F = valve_case->mesh.F;
  if (V.rows() != valve_case->mesh.V.rows() || F.rows() != case_F.rows()) {
    diagnostics.error(options.mesh_file, "",
                      "mesh does not have the case mesh's topology (" + std::to_string(V.rows()) +
                          " vertices / " + std::to_string(F.rows()) + " triangles vs " +
                          std::to_string(valve_case->mesh.V.rows()) + " / " +
                          std::to_string(case_F.rows()) + ")");
    return reportProblems(diagnostics);
  }
  // The same counts: name the first triangle that differs (a flipped or renumbered face).
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    if (F.row(f) == case_F.row(f)) continue;
    auto corners = [](const Eigen::MatrixXi& faces, Eigen::Index row) {
      return std::to_string(faces(row, 0)) + " " + std::to_string(faces(row, 1)) + " " +
             std::to_string(faces(row, 2));
    };
    diagnostics.error(options.mesh_file, "faces[" + std::to_string(f) + "]",
                      "vertices " + corners(F, f) + " where the case mesh has " +
                          corners(case_F, f) +
                          ": the closed mesh must keep the case mesh's triangles in their order");
    return reportProblems(diagnostics);
  }
  // A closed valve stays within reach of its open state (case_extent.h).
  if (!checkPointsNearValve(valve_case->mesh.V, V, options.mesh_file, "vertices", diagnostics) ||
      !checkMesh(V, F, options.mesh_file, diagnostics))
    return reportProblems(diagnostics);
  const ValveMetrics metrics = computeMetrics(*valve_case, V);
  std::cout << table1Header() << table1Row(valve_case->name, metrics);
  char highest[64];
  std::snprintf(highest, sizeof highest, "%.2f", metrics.mesh_prolapse.max_height_mm);
  std::cout << closedValveSummary(metrics)
            << "highest point above the annular hinge line: " << highest << " mm\n";
  if (!options.out_file.empty()) {
    writeFileAtomically(options.out_file, metricsJson(metrics).dump(2) + "\n");
    forgetPublished(options.out_file);  // now the user's file (staged_output.h)
    std::cout << "wrote " << options.out_file << "\n";
  }
  return kExitOk;
}

}  // namespace chordfit::cli
