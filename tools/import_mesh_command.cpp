// import-mesh: a case directory from a segmented open-state valve mesh and three landmarks
// (core/case_import.h), written to a temporary sibling directory, validated by loading it
// back, and only then moved into place, so a failure leaves nothing behind.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <system_error>

#include "core/case_import.h"
#include "core/case_io.h"
#include "core/curve_io.h"
#include "core/mesh_io.h"
#include "tools/command_support.h"
#include "tools/commands.h"

namespace chordfit::cli {

namespace fs = std::filesystem;

namespace {

// The anterior annulus is about a third of the circumference (Ranganathan et al. 1970);
// outside this range the landmarks are probably swapped or misplaced.
constexpr double kAnteriorFractionLow = 0.2, kAnteriorFractionHigh = 0.5;

int fail(const std::string& file, const std::string& what) {
  std::cerr << "error: " << file << ": " << what << "\n";
  return kExitBadInput;
}

}  // namespace

int runImportMesh(const ImportMeshOptions& options) {
  const fs::path out(options.out_dir);
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_empty(out, ec)) {
    return fail(options.out_dir, "exists and is not empty; give a new directory for the case");
  }
  Diagnostics diagnostics;
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Curve landmarks, closed, tips;
  readMesh(options.mesh_file, V, F, diagnostics, options.mesh_file);
  readCurve(options.landmarks_file, landmarks, diagnostics, options.landmarks_file);
  if (!options.closed_annulus_file.empty()) {
    readCurve(options.closed_annulus_file, closed, diagnostics, options.closed_annulus_file);
  }
  if (!options.pm_tips_file.empty()) {
    readCurve(options.pm_tips_file, tips, diagnostics, options.pm_tips_file);
  }
  std::vector<Tracing> tracings;
  if (!options.tracings_file.empty()) {
    readTracingsFile(options.tracings_file, ValveMesh{}.leaflet_names, tracings, diagnostics);
  }
  if (!diagnostics.ok()) return reportProblems(diagnostics);
  if (landmarks.points.rows() != 3) {
    return fail(options.landmarks_file,
                "expected 3 points (anterolateral commissure, posteromedial commissure, a point "
                "of the anterior annulus), got " +
                    std::to_string(landmarks.points.rows()));
  }
  ImportLandmarks l;
  l.anterolateral = landmarks.points.row(0).transpose();
  l.posteromedial = landmarks.points.row(1).transpose();
  l.anterior = landmarks.points.row(2).transpose();
  const std::string name = options.name.empty() ? out.filename().string() : options.name;
  ImportedCase imported = importValveCase(V, F, l, closed.points, name);
  if (!imported.ok()) return fail(options.mesh_file, imported.error);
  imported.valve_case.tracings = tracings;
  if (tips.points.rows() > 0) {
    std::vector<PmTip> pm_tips;
    for (Eigen::Index t = 0; t < tips.points.rows(); ++t) {
      PmTip tip;
      tip.name = tips.points.rows() == 2 ? (t == 0 ? "anterolateral" : "posteromedial")
                                         : "tip-" + std::to_string(t + 1);
      tip.position = tips.points.row(t).transpose();
      pm_tips.push_back(tip);
    }
    imported.valve_case.tips = pm_tips;
  }

  // Write beside the target, load it back (every check of `validate`), then move it in place.
  fitStepCapToMesh(imported.valve_case);
  const fs::path staging = out.parent_path() / (out.filename().string() + ".import-tmp");
  fs::remove_all(staging, ec);
  writeCase(staging, imported.valve_case);
  Diagnostics check;
  const auto loaded = loadCase(staging, check);
  if (!loaded) {
    fs::remove_all(staging, ec);
    std::cerr << "error: import-mesh: the imported case does not validate:\n";
    check.print(std::cerr);
    return kExitBadInput;
  }
  fs::remove(out, ec);  // an empty directory, if any
  fs::rename(staging, out);

  const ValveCase& c = imported.valve_case;
  std::printf("import-mesh: %s -> %s\n", options.mesh_file.c_str(), options.out_dir.c_str());
  std::printf(
      "  annulus ring: %ld boundary vertices; commissure landmarks %.2f and %.2f mm from "
      "it\n",
      static_cast<long>(c.mesh.annulus.size()), imported.commissure_distance_mm[0],
      imported.commissure_distance_mm[1]);
  std::printf(
      "  anterior arc: %.0f %% of the annulus; leaflet vertices: anterior %ld, posterior "
      "%ld\n",
      100.0 * imported.anterior_fraction, static_cast<long>((c.mesh.leaflet.array() == 0).count()),
      static_cast<long>((c.mesh.leaflet.array() == 1).count()));
  if (imported.anterior_fraction < kAnteriorFractionLow ||
      imported.anterior_fraction > kAnteriorFractionHigh) {
    std::printf(
        "warning: the anterior annulus is usually about a third of the circumference; "
        "check the landmarks' order (anterolateral, posteromedial, anterior)\n");
  }
  if (options.closed_annulus_file.empty()) {
    std::printf("  closed annulus: none given, the annulus stays at its open position\n");
  } else {
    std::printf(
        "  closed annulus: %s, resampled onto the ring; mean shift from the open ring "
        "%.2f mm\n",
        options.closed_annulus_file.c_str(), imported.closed_shift_mm);
  }
  std::cout << caseSummary(*loaded);
  if (tracings.empty()) {
    std::printf(
        "next: add the tracings of the closed valve (--tracings, or docs/case-format.md "
        "\"tracings\") to fit; `chordfit simulate %s --out DIR` closes it with the "
        "heuristic cords\n",
        options.out_dir.c_str());
  } else {
    std::printf("next: `chordfit fit %s --out DIR` fits the cords to the tracings\n",
                options.out_dir.c_str());
  }
  return kExitOk;
}

}  // namespace chordfit::cli
