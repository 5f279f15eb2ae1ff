// The chordfit commands behind plain option structs. main.cpp (the only file that sees CLI11)
// parses the command line into these and calls run*. Each returns the process exit code:
//   0 success, 1 unexpected failure (e.g. cannot write output), 2 bad input or usage,
//   3 simulation failure (divergence).
#pragma once

#include <string>
#include <vector>

#include "core/parametric_valve.h"

namespace chordfit::cli {

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitSimulationFailed = 3;

struct ValidateOptions {
  std::string case_dir;
};
int runValidate(const ValidateOptions& options);

struct MakeValveOptions {
  std::string out_dir;
  std::string annulus_file;  // optional user annulus polyline
  std::string name = "parametric-mitral";
  // Anatomy and mesh resolution (target_edge_mm, --edge); the defaults of ValveParameters.
  ValveParameters parameters;
  // The options given on the command line ("--ap"), for a note on those --annulus overrides.
  std::vector<std::string> given_options;
};
int runMakeValve(const MakeValveOptions& options);
// The case's files (caseFileNames, core/case_io.h). The pre-flight checks these names and
// StagedOutput refuses any other (tools/staged_output.h); likewise for each *OutputFiles.
std::vector<std::string> makeValveOutputFiles();

struct HeuristicCommandOptions {
  std::string case_dir;
  std::string out_file;
  double primary_spacing_mm = 4.0;
  double secondary_spacing_mm = 6.0;
  double secondary_depth_mm = 7.0;
  double primary_compliance = 0.0;    // mm/N, HeuristicOptions::primary_compliance_mm_per_n
  double secondary_compliance = 0.0;  // mm/N
};
int runHeuristic(const HeuristicCommandOptions& options);

struct MetricsOptions {
  // Simulator settings over the case's "simulation" block: "KEY=VALUE" (--set), as simulate
  // closed the mesh with (the orifice coverage reads the contact thickness).
  std::vector<std::string> settings_overrides;
  std::string case_dir;
  std::string mesh_file;
  std::string out_file;  // optional
};
int runMetrics(const MetricsOptions& options);

}  // namespace chordfit::cli

namespace chordfit::cli {

struct SimulateOptions {
  // Simulator settings over the case's "simulation" block: "KEY=VALUE" (--set).
  std::vector<std::string> settings_overrides;
  std::string case_dir;
  std::string cords_file;       // optional; else the case's cords, else the heuristic
  std::string tissue_file;      // optional; else the case's tissue (uniform when it has none)
  std::string phase = "close";  // close | open (open = close, then open from the closed state)
  std::string out_dir;
  // Threads of the closure (SimulationSettings::threads): the same bytes for any count.
  int threads = 2;
  bool quiet = false;
  bool sections = true;  // sections.svg (fit writes its own, with the seed closure beside it)
  // The "wrote ..." line; off when another command (fit) simulates into its own staging
  // directory and lists the files it publishes.
  bool report_files = true;
};
int runSimulate(const SimulateOptions& options);
// The files a closure writes into its output directory (closed.*, opened.* with --phase open,
// metrics.json, enface.svg); simulate adds sections.svg. The pre-flight checks these names
// and StagedOutput refuses any other (tools/staged_output.h); likewise for each *OutputFiles.
std::vector<std::string> closureOutputFiles(bool open_phase);
std::vector<std::string> simulateOutputFiles(const SimulateOptions& options);

}  // namespace chordfit::cli

#include <cstdint>

namespace chordfit::cli {

// make-case: a synthetic case with ground truth (core/synthetic_case.h).
struct MakeCaseOptions {
  std::string preset;
  std::string out_dir;
  std::uint64_t seed = 1;
  int planes = 6;
  double noise_mm = 0.3;
  double dropout = 0.1;
  double edge_mm = 1.5;
  int threads = 2;                  // of the truth closure (the same truth for any count)
  bool attach_at_vertices = false;  // cords at the nearest vertex of each mesh (older cohorts)
  bool list = false;                // print the presets and exit
  bool quiet = false;
};
int runMakeCase(const MakeCaseOptions& options);
// Whether `word` names a cohort preset: "make-case prolapse-P2" meant --preset prolapse-P2.
bool isPresetName(const std::string& word);
// The case's files and the truth's under truth/ (syntheticCaseFileNames, core/synthetic_case.h).
std::vector<std::string> makeCaseOutputFiles();

}  // namespace chordfit::cli

namespace chordfit::cli {

struct SweepCordOptions {
  // Simulator settings over the case's "simulation" block: "KEY=VALUE" (--set).
  std::vector<std::string> settings_overrides;
  std::string case_dir;
  std::string cords_file;   // optional; as for simulate
  std::string tissue_file;  // optional; as for simulate
  int cord = -1;            // cord index; -1: the P2 primary cord nearest the P2 centre
  double range = 0.05;      // sweep scale over [1 - range, 1 + range]
  double step = 0.001;      // scale step
  int window = 5;           // half-width (points) of the local quadratic fit for the noise
  int threads = 2;
  std::string out_dir;
  bool quiet = false;  // no progress lines
};
int runSweepCord(const SweepCordOptions& options);
std::vector<std::string> sweepCordOutputFiles();

}  // namespace chordfit::cli

#include <vector>

namespace chordfit::cli {

// compare: close the case once per cord set, Table 1 side by side (issue 5 item 6).
struct CompareOptions {
  // Simulator settings over the case's "simulation" block: "KEY=VALUE" (--set).
  std::vector<std::string> settings_overrides;
  std::string case_dir;
  std::vector<std::string> cords_files;  // one or more CordSet JSON files
  std::string labels;                    // "a,b,...": one per file; default the file names
  std::string tissues;  // "t1,-,...": one regional tissue file per cord file, "-" = the case's
  std::string out_dir;  // optional: compare.md + compare.csv
  int threads = 2;      // the cord sets' closures run in parallel (the same output for any count)
  bool quiet = false;
};
int runCompare(const CompareOptions& options);
std::vector<std::string> compareOutputFiles(const CompareOptions& options);
// The cord and tissue files compare reads (not the case's own).
std::vector<std::string> compareInputFiles(const CompareOptions& options);

}  // namespace chordfit::cli

#include <vector>

namespace chordfit::cli {

// fit: inverse fit of the cord rest lengths (and optionally the PM tips) to the tracings
// (issue 5; inverse/fit_cords.h).
struct FitCommandOptions {
  // Simulator settings over the case's "simulation" block: "KEY=VALUE" (--set).
  std::vector<std::string> settings_overrides;
  std::string case_dir;
  std::string seed_cords_file;      // optional; else the case's cords, else the heuristic
  std::string params = "scales";    // scales | groups | scales+tips
  std::string optimizer = "ceres";  // ceres | bobyqa | cobyla | sbplx | crs2
  int max_sims = 400;               // the fit's closures (not the one written out)
  int threads = 2;
  std::vector<double> scale_bounds{0.7, 1.5};
  double tip_box_mm = 8.0;
  double tip_weight = 0.05;        // RegularisationWeights::tip_per_mm
  bool prefit = true;              // global and segment pre-fits before the optimiser
  bool tissue_prefit = false;      // softer tissue per segment, after the cord pre-fits
  bool tissue_retry = true;        // fit again with the tissue pre-fit when a prolapse is missed
  bool slack_release = true;       // slack cords to the kind's typical scale at the end
  double fd_scale_step = 0.01;     // central-difference step on a scale
  double fd_tip_step_mm = 0.1;     // ... on a tip offset coordinate
  bool fd_warm_start = false;      // perturbed closures start from the base closed state
  bool fd_slack_closures = false;  // also close the perturbations of slack-only parameters
  std::string distance = "own-leaflet";  // own-leaflet | surface (inverse/forward_residual.h)
  double section_weight = 0.0;           // ResidualOptions::section_weight
  bool uncertainty = true;               // FitOptions::uncertainty
  std::string out_dir;
  bool quiet = false;
  // The options given on the command line ("--tip-box"), for notes on those that do not act
  // in this fit (after the values are checked).
  std::vector<std::string> given_options;
};
int runFit(const FitCommandOptions& options);
std::vector<std::string> fitOutputFiles();

}  // namespace chordfit::cli

namespace chordfit::cli {

// edit-cords: the paper's cord editor on the command line. A scale multiplies a cord's seed
// rest length (rest = seed_rest_length * scale, the paper's "scale cord lengths"); edited
// cords become provenance manual; locked cords are left alone. Applied in this order, so the
// more specific wins: --unlock, --all, --group, --segment, --cord, --lock. --move-tip moves a
// PM tip (its open and, when present, closed position, as the fit's tip offsets do); rest
// lengths stay.
struct EditCordsOptions {
  std::string case_dir;
  std::string cords_file;  // optional; else the case's cords, else the heuristic
  std::string out_file;
  std::string all_scale;                    // "S" (empty: none)
  std::vector<std::string> group_scales;    // "anterior/anterolateral=S" (leaflet/tip)
  std::vector<std::string> segment_scales;  // "P2=S" (Carpentier segment of the cord's vertex)
  std::vector<std::string> cord_scales;     // "K=S" (cord index, 0-based)
  std::vector<std::string> tip_moves;       // "NAME=DX,DY,DZ" (mm): a PM tip moved
  std::string lock;                         // "K,K,..." | "edited" | "all" (empty: none)
  std::string unlock;                       // "K,K,..." | "all" (empty: none)
};
int runEditCords(const EditCordsOptions& options);

}  // namespace chordfit::cli

namespace chordfit::cli {

// import-mesh: a case from a segmented open-state valve mesh and three landmarks
// (core/case_import.h); the annulus ring, leaflet labels and closed annulus are derived.
struct ImportMeshOptions {
  std::string mesh_file;
  std::string landmarks_file;       // curve file: AL commissure, PM commissure, anterior point
  std::string closed_annulus_file;  // optional curve file: the closed-state annulus
  std::string tracings_file;        // optional tracings file (docs/case-format.md)
  std::string pm_tips_file;         // optional curve file: PM tips, anterolateral first
  std::string name;                 // default: the output directory's name
  std::string out_dir;
  bool keep_seams = false;  // coincident vertices stay apart (default: welded)
};
int runImportMesh(const ImportMeshOptions& options);
// The case's files, as make-valve's.
std::vector<std::string> importMeshOutputFiles();

}  // namespace chordfit::cli
