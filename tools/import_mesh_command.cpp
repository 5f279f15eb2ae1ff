// import-mesh: a case directory from a segmented open-state valve mesh and three landmarks
// (core/case_import.h), written to a staging directory, validated by loading it back, and only
// then published (tools/staged_output.h), so a failure leaves the directory as it was.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "core/case_import.h"
#include "core/case_io.h"
#include "core/curve_io.h"
#include "core/mesh_io.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/staged_output.h"

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

// "point 3", "points 1 and 2": the landmarks at fault as the points of the --landmarks file,
// counted from 1 in the file's order, which is the one thing every curve format shares.
std::string landmarkPoints(const std::vector<int>& landmarks) {
  std::string text = landmarks.size() == 1 ? "point " : "points ";
  for (std::size_t k = 0; k < landmarks.size(); ++k) {
    if (k > 0) text += k + 1 == landmarks.size() ? " and " : ", ";
    text += std::to_string(landmarks[k] + 1);
  }
  return text;
}

// An import error under the input that gave what is wrong: the mesh file, the point of the
// --landmarks file, or the --closed-annulus file.
int failImport(const ImportMeshOptions& options, const ImportedCase& imported) {
  switch (imported.error_input) {
    case ImportInput::kLandmarks:
      return fail(options.landmarks_file,
                  landmarkPoints(imported.error_landmarks) + ": " + imported.error);
    case ImportInput::kClosedAnnulus:
      return fail(options.closed_annulus_file, imported.error);
    case ImportInput::kMesh:
      break;
  }
  return fail(options.mesh_file, imported.error);
}

// The first file of `staging` that would replace one in `out` that no chordfit run wrote, or
// nullopt. The inputs are the user's own files and often sit where the case goes (the mesh as
// open.ply, the tracings as tracings.json): those are refused, not replaced; an earlier
// import's or make-valve's files are replaced.
std::optional<fs::path> userFileInTheWay(const fs::path& staging, const fs::path& out) {
  for (const fs::directory_entry& entry : fs::directory_iterator(staging)) {
    const fs::path file = out / entry.path().filename();
    std::error_code ec;
    if (fs::exists(fs::symlink_status(file, ec)) && !publishedByChordfit(file)) return file;
  }
  return std::nullopt;
}

// Writes the case into a staging directory in `out`, loads it back with every check of
// `validate`, and publishes it unless it would replace a file of the user's. On a problem
// prints it and returns nullopt, leaving `out` as it was (removed again when this created it).
std::optional<StagedOutput::Published> writeValidatedCase(const fs::path& out,
                                                          const ValveCase& valve_case,
                                                          ValveCase& loaded) {
  std::error_code ec;
  const bool out_existed = fs::exists(out, ec);
  {
    const std::vector<std::string> files = importMeshOutputFiles();
    StagedOutput staged(out, files, caseDirectoryFilesBesides(files));
    writeCase(staged.dir(), valve_case);
    Diagnostics check;
    std::optional<ValveCase> read_back = loadCase(staged.dir(), check);
    const std::optional<fs::path> in_the_way = userFileInTheWay(staged.dir(), out);
    if (!read_back) {
      std::cerr << "error: import-mesh: the imported case does not validate:\n";
      check.print(std::cerr);
    } else if (in_the_way) {
      std::cerr << "error: import-mesh: --out: " << in_the_way->string()
                << ": exists and was not written by chordfit; import-mesh does not replace it "
                   "(give a new directory for the case, or move the file)\n";
    } else {
      loaded = std::move(*read_back);
      return staged.publish();
    }
  }
  if (!out_existed) fs::remove(out, ec);  // empty again once the staging directory is gone
  return std::nullopt;
}

}  // namespace

int runImportMesh(const ImportMeshOptions& options) {
  const fs::path out(options.out_dir);
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
  if (!imported.ok()) return failImport(options, imported);
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

  fitStepCapToMesh(imported.valve_case);
  ValveCase loaded;
  const std::optional<StagedOutput::Published> published =
      writeValidatedCase(out, imported.valve_case, loaded);
  if (!published) return kExitBadInput;

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
  std::cout << caseSummary(loaded) << wroteLine(out, *published) << "\n";
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

std::vector<std::string> importMeshOutputFiles() { return caseFileNames(); }

}  // namespace chordfit::cli
