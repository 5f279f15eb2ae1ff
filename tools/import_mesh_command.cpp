// import-mesh: a case directory from a segmented open-state valve mesh and three landmarks
// (core/case_import.h), written to a staging directory, validated by loading it back, and only
// then published (tools/staged_output.h), so a failure leaves the directory as it was.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "core/annulus_plane.h"
#include "core/case_extent.h"
#include "core/case_import.h"
#include "core/case_io.h"
#include "core/cgal_backend.h"
#include "core/counted.h"
#include "core/curve_io.h"
#include "core/leaflet_agreement.h"
#include "core/mesh_io.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/shell_word.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

namespace fs = std::filesystem;

namespace {

// The anterior annulus is about a third of the circumference (Ranganathan et al. 1970);
// outside this range the landmarks are probably swapped or misplaced.
constexpr double kAnteriorFractionLow = 0.2, kAnteriorFractionHigh = 0.5;
bool plausibleAnteriorFraction(double fraction) {
  return fraction >= kAnteriorFractionLow && fraction <= kAnteriorFractionHigh;
}

std::string percent(double fraction) {
  return std::to_string(static_cast<int>(std::lround(100.0 * fraction))) + " %";
}

// The landmarks in rows `al`, `pm`, `anterior` of `points` (the file's order is 0, 1, 2).
ImportLandmarks landmarksOfRows(const Eigen::MatrixXd& points, int al, int pm, int anterior) {
  return {points.row(al).transpose(), points.row(pm).transpose(), points.row(anterior).transpose()};
}

// For an implausible anterior share: another order of the three landmarks under which it is
// plausible, in words, or "" (then the valve may just be unusual, or a point misplaced, and the
// import only warns).
// Points are 0-based rows of `points` in the file's order (AL, PM, anterior).
std::string landmarkOrderProblem(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                 const Eigen::MatrixXd& points) {
  for (int anterior : {0, 1}) {
    const int first = anterior == 0 ? 1 : 0;  // the other two, in the file's order
    const ImportedCase other = importValveCase(V, F, landmarksOfRows(points, first, 2, anterior),
                                               Eigen::MatrixXd(), "probe");
    if (other.ok() && plausibleAnteriorFraction(other.anterior_fraction)) {
      return "with point " + std::to_string(anterior + 1) + " as the anterior point it is " +
             percent(other.anterior_fraction) +
             ": are the points in another order? The file's order is the anterolateral "
             "commissure, the posteromedial commissure, a point of the anterior annulus";
    }
  }
  return "";
}

// Two papillary-muscle tips in the file's order (anterolateral, posteromedial) against the
// valve's lateral axis (annulus_plane.h, +l anterolateral), or "" when they agree. Swapped,
// every cord's group would name the other muscle.
std::string pmTipOrderProblem(const ValveMesh& mesh, const std::vector<PmTip>& tips) {
  if (const auto [i, j] = tipsTooClose(tips); j >= 0)
    return "points " + std::to_string(i + 1) + " and " + std::to_string(j + 1) +
           " are less than 1 mm apart: each papillary muscle needs its own tip";
  if (tips.size() != 2) return "";
  const AnnulusFrame frame = openAnnulusFrame(mesh);
  const double al = frame.l.dot(tips[0].position - frame.plane.centre);
  const double pm = frame.l.dot(tips[1].position - frame.plane.centre);
  if (al >= pm) return "";
  char text[320];
  std::snprintf(text, sizeof text,
                "point 1 (the anterolateral tip) lies %.1f mm farther to the posteromedial side "
                "than point 2 (the posteromedial tip): are they swapped? The file's order is "
                "anterolateral, posteromedial",
                pm - al);
  return text;
}

// For a file whose points fit once x and y are negated: the question to ask.
std::string frameHint(const Curve& curve) {
  return " (with x and y negated the points fit: " + otherFrameQuestion(&curve) + ")";
}

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

// The row of a list field a case check names ("points[4]", "tips[1].position": 4, 1), or -1
// when `where` is not in the list `list`.
int listRow(const std::string& where, const std::string& list) {
  const std::string prefix = list + "[";
  if (where.rfind(prefix, 0) != 0) return -1;
  return std::atoi(where.c_str() + prefix.size());
}

// "point 5" for row 4: a point of the user's curve file, counted from 1 in the file's order as
// the landmarks are (landmarkPoints).
std::string pointOfFile(int row) { return "point " + std::to_string(row + 1); }

// A problem of the staged case's read-back under the input the user gave for that file: the
// staged names (annulus_closed.json, pm_tips.json) are files the user never saw, and the closed
// annulus's rows are ring positions after resampling, not the --closed-annulus file's points.
// The files import-mesh derives itself (labels, ring) keep their names.
Problem asTheUsersInput(Problem problem, const ImportMeshOptions& options) {
  if (problem.file == "open.ply") {
    problem.file = options.mesh_file;  // written as read: the same vertices and triangles
  } else if (problem.file == "annulus_closed.json" && !options.closed_annulus_file.empty()) {
    problem.file = options.closed_annulus_file;
    const int row = listRow(problem.where, "points");
    problem.where = "after resampling onto the annulus ring" +
                    (row >= 0 ? ", at ring position " + std::to_string(row + 1) : "");
  } else if (problem.file == "pm_tips.json" && !options.pm_tips_file.empty()) {
    problem.file = options.pm_tips_file;  // one tip per point, in the file's order
    if (const int row = listRow(problem.where, "tips"); row >= 0) problem.where = pointOfFile(row);
  } else if (problem.file == "tracings.json" && !options.tracings_file.empty()) {
    problem.file = options.tracings_file;  // the same tracings in the same order
  }
  return problem;
}

// Each point of the user's closed annulus curve within reach of the valve (case_extent.h),
// named by its place in the file: checked on the case's resampled annulus, a far point was
// named as a ring position of annulus_closed.json.
bool closedAnnulusNearValve(const Eigen::MatrixXd& V, const Curve& closed, const std::string& file,
                            Diagnostics& diagnostics) {
  Diagnostics far;
  if (checkPointsNearValve(V, closed.points, file, "points", far)) return true;
  for (Problem problem : far.problems()) {
    if (const int row = listRow(problem.where, "points"); row >= 0)
      problem.where = pointOfFile(row);
    diagnostics.error(problem.file, problem.where, problem.what);
  }
  return false;
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
// prints it and returns nullopt, leaving `out` as it was (StagedOutput removes it again when
// it created it).
std::optional<StagedOutput::Published> writeValidatedCase(const fs::path& out,
                                                          const ValveCase& valve_case,
                                                          const ImportMeshOptions& options,
                                                          ValveCase& loaded) {
  const std::vector<std::string> files = importMeshOutputFiles();
  StagedOutput staged(out, files, caseDirectoryFilesBesides(files), kCaseWriter);
  writeCase(staged.dir(), valve_case);
  Diagnostics check;
  std::optional<ValveCase> read_back = loadCase(staged.dir(), check);
  if (!read_back) {
    std::cerr << "error: import-mesh: the imported case does not validate:\n";
    Diagnostics named;
    for (const Problem& problem : check.problems()) {
      const Problem p = asTheUsersInput(problem, options);
      named.error(p.file, p.where, p.what);
    }
    named.print(std::cerr);
    return std::nullopt;
  }
  if (const std::optional<fs::path> in_the_way = userFileInTheWay(staged.dir(), out)) {
    std::cerr << "error: import-mesh: --out: " << in_the_way->string()
              << ": exists and was not written by chordfit; import-mesh does not replace it "
                 "(give a new directory for the case, or move the file)\n";
    return std::nullopt;
  }
  loaded = std::move(*read_back);
  return staged.publish();
}

}  // namespace

int runImportMesh(const ImportMeshOptions& options) {
  // The check loadCase makes of case.json's name, up front and as the option's: the staged case
  // used to be refused when read back, as case.json's, a name the user may never have given. No
  // --name (or "") names the case after its output directory, also when given as "dir/" or ".".
  const fs::path out(options.out_dir);
  fs::path named = fs::absolute(out).lexically_normal();
  if (named.filename().empty()) named = named.parent_path();
  const std::string name = options.name.empty() ? named.filename().string() : options.name;
  if (const std::string problem = caseNameProblem(name); !problem.empty()) {
    if (!options.name.empty()) return fail("import-mesh", "--name: " + problem);
    return fail("import-mesh", "--out '" + out.string() +
                                   "': without --name the case is named after this directory, "
                                   "whose name " +
                                   problem.substr(0, problem.find(':')) + "; give --name");
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
  // The mesh as a case's loader checks it, before the import reads it at its face indices (an
  // index past the vertices crashed the boundary walk) and before the landmarks are judged
  // against it (a mesh in metres made every landmark "130 mm from the nearest boundary loop").
  // Exporters that write each triangle with its own corners leave a mesh of separate
  // triangles, whose boundary loops are every triangle's rim: the landmarks were then blamed
  // ("24 mm from the nearest boundary loop"). A segmentation's surface is one sheet: weld it,
  // unless the user keeps a seam open on purpose (--keep-seams).
  if (!options.keep_seams && diagnostics.ok() && V.allFinite() &&
      (F.size() == 0 || (F.minCoeff() >= 0 && F.maxCoeff() < V.rows()))) {
    if (const int merged = weldCoincidentVertices(V, F); merged > 0)
      printNote(
          "import-mesh: %s: %s merged into others at the same position, %s left (an "
          "exporter that repeats each triangle's corners leaves separate triangles; "
          "--keep-seams keeps them apart)\n",
          options.mesh_file.c_str(), counted(merged, "vertex", "vertices").c_str(),
          counted(V.rows(), "vertex", "vertices").c_str());
  }
  if (diagnostics.ok()) checkValveMesh(V, F, options.mesh_file, diagnostics);
  if (diagnostics.ok() && closed.points.rows() > 0)
    closedAnnulusNearValve(V, closed, options.closed_annulus_file, diagnostics);
  if (!diagnostics.ok()) return reportProblems(diagnostics);
  if (landmarks.points.rows() != 3) {
    return fail(options.landmarks_file,
                "expected 3 points (anterolateral commissure, posteromedial commissure, a point "
                "of the anterior annulus), got " +
                    std::to_string(landmarks.points.rows()));
  }
  const ImportLandmarks l = landmarksOfRows(landmarks.points, 0, 1, 2);
  ImportedCase imported = importValveCase(V, F, l, closed.points, name);
  if (!imported.ok()) {
    // RAS read as LPS (or the reverse) turns a file half a turn about S: say so when the
    // file at fault fits once its x and y are negated.
    auto turned = [](Eigen::MatrixXd points) {
      points.leftCols(2) *= -1.0;
      return points;
    };
    if (imported.error_input == ImportInput::kLandmarks) {
      if (importValveCase(V, F, landmarksOfRows(turned(landmarks.points), 0, 1, 2),
                          Eigen::MatrixXd(), name)
              .ok())
        imported.error += frameHint(landmarks);
    } else if (imported.error_input == ImportInput::kClosedAnnulus &&
               importValveCase(V, F, l, turned(closed.points), name).ok()) {
      imported.error += frameHint(closed);
    }
    return failImport(options, imported);
  }
  if (!plausibleAnteriorFraction(imported.anterior_fraction)) {
    const std::string problem = landmarkOrderProblem(V, F, landmarks.points);
    if (!problem.empty())
      return fail(options.landmarks_file, "the anterior arc is " +
                                              percent(imported.anterior_fraction) +
                                              " of the annulus, usually about a third; " + problem);
  }
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
    if (const std::string problem = pmTipOrderProblem(imported.valve_case.mesh, pm_tips);
        !problem.empty())
      return fail(options.pm_tips_file, problem);
    imported.valve_case.tips = pm_tips;
  }

  fitStepCapToMesh(imported.valve_case);
  ValveCase loaded;
  const std::optional<StagedOutput::Published> published =
      writeValidatedCase(out, imported.valve_case, options, loaded);
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
  if (imported.holes > 0) {
    // A hole lets the leaflet's edge there hang free: the closure and the labels near it
    // differ from the tissue's.
    printWarning(
        "the mesh has %d boundary loop(s) besides the annulus and the free edge: holes "
        "in the leaflet surface (a missing triangle?) or loose pieces; each such edge is "
        "simulated as free\n",
        imported.holes);
  }
  if (!plausibleAnteriorFraction(imported.anterior_fraction)) {
    const double other = 1.0 - imported.anterior_fraction;
    const std::string cause =
        plausibleAnteriorFraction(other)
            ? ": point 3 may lie on the posterior annulus, or a commissure be misplaced (the "
              "other arc is " +
                  percent(other) + ")"
            : "";
    printWarning(
        "the anterior annulus is usually about a third of the circumference; check "
        "the landmarks (anterolateral, posteromedial, anterior)%s\n",
        cause.c_str());
  }

  if (const double agreement = tracingLeafletAgreement(c.mesh, c.tracings);
      std::isfinite(agreement)) {
    std::printf("  tracing points nearest to their own leaflet (open state): %.0f %%\n",
                100.0 * agreement);
    // 65-80 % on the synthetic cohort's cases (66-80 % over every preset); 35 % measured with
    // landmarks in RAS read as LPS on a valve centred at the origin.
    if (agreement < kLeafletAgreementLow)
      printWarning(
          "most tracing points are nearer the other leaflet (65-80 %% lie nearest their "
          "own on correctly labelled valves): are the landmarks and the tracings in the same "
          "coordinate system (RAS read as LPS)? Check the leaflet vertex counts above\n");
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
        shellWord(options.out_dir).c_str());
  } else {
    std::printf("next: `chordfit fit %s --out DIR` fits the cords to the tracings\n",
                shellWord(options.out_dir).c_str());
  }
  return kExitOk;
}

std::vector<std::string> importMeshOutputFiles() { return caseFileNames(); }

}  // namespace chordfit::cli
