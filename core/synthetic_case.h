// A synthetic case with known ground truth (DESIGN §8, issue "Synthetic cohort"):
//   1. patient:   a preset's anatomy varied by the seed (cohort_presets.h);
//   2. meshes:    the same parametric anatomy at the case resolution (edge) and at a finer one
//                 (edge * truth_edge_ratio) for the truth, so the fitter never sees the mesh
//                 the tracings came from (no "inverse crime");
//   3. cords:     one anatomical layout (cord_attachments.h) mapped to both meshes, so truth
//                 and case cords correspond one to one, in the same order; PM tips and seed
//                 rest lengths by the paper's heuristic on each mesh; the truth's rest lengths
//                 are the heuristic's times the true scales (cohort_presets.h), its tips are
//                 moved by a small seeded offset;
//   4. truth:     the fine valve closed with the true cords under tighter solver settings;
//   5. tracings:  sampled from the true closed mesh (tracing_sampler.h);
//   6. noise floor: computeMetrics of the true closed mesh against the tracings.
// The case (what a fitter sees) holds the coarse open mesh, annulus, tracings and the
// heuristic cord set (provenance heuristic, scale 1: the fitter's seed). Everything true goes
// to truth/ (writeSyntheticCase); nothing in the case refers to it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/case_data.h"
#include "core/cohort_presets.h"
#include "core/cord_attachments.h"
#include "core/metrics.h"
#include "core/parametric_valve.h"
#include "core/simulator.h"
#include "core/tracing_sampler.h"

namespace chordfit {

// The case mesh edges `make-case` (and the benchmark's --edge) accept, mm: finer than 1 mm
// gives a truth finer than 0.5 mm, which has not been seen to close (tools/make_case_command.cpp).
constexpr double kMinCaseEdgeMm = 1.0, kMaxCaseEdgeMm = 5.0;

struct SyntheticCaseOptions {
  std::string preset;
  // Used instead of the named preset when set (experiments, calibration); `preset` then only
  // names the case.
  std::optional<CohortPreset> custom_preset;
  std::uint64_t seed = 1;
  double edge_mm = 1.5;           // case mesh resolution
  double truth_edge_ratio = 0.5;  // truth mesh edge = edge_mm * ratio
  double tip_offset_sd_mm = 0.5;  // per-axis SD of the true PM tips' offset from the heuristic
  TracingSamplerOptions tracing;
  AttachmentLayoutOptions layout;
  // Cords insert at their anatomical points on both meshes (pointAttachments, the default),
  // or at the vertex nearest to that point on each mesh (mapAttachments, what the cohort did
  // before it had points): then truth and case cords pull on places up to half an edge apart.
  bool attach_at_vertices = false;
  // Solver settings of the truth closure; default truthSimulationSettings().
  std::optional<SimulationSettings> truth_settings;
  // Threads of the truth closure (SimulationSettings::threads; the same truth for any count).
  int threads = 1;
  // Stage messages ("building meshes", ...) and simulator progress; both optional.
  std::function<void(const std::string&)> message;
  std::function<void(const SimulationProgress&)> simulation_progress;
};

struct SyntheticCase {
  SyntheticCaseOptions options;
  CohortPreset preset;
  ValveParameters anatomy;  // the patient's (target_edge_mm = the case edge)
  ValveCase valve_case;     // what a fitter sees; cords = heuristic seed
  // The fine valve as a case: same tracings, cords = the true cords, simulation block = the
  // tight solver settings (so `chordfit simulate truth/case` reproduces the truth).
  ValveCase truth_case;
  std::vector<AnatomicalAttachment> attachments;
  std::vector<int> case_vertices, truth_vertices;    // per attachment (a point's largest weight)
  std::vector<CordPoint> case_points, truth_points;  // per attachment; empty at vertices
  std::vector<double> true_scales;                   // per cord: true rest / heuristic seed
  std::vector<bool> ruptured;                        // per cord
  SimulationSettings truth_settings;
  int truth_retries = 0;          // time-step halvings the truth closure needed (0: none)
  SimulationResult truth_result;  // V: the true closed state of truth_case.mesh
  ValveMetrics truth_metrics;     // true closed mesh vs tracings: the noise floor
  std::string cross_sections_svg;
  double seconds = 0.0;  // generation wall time
};

// The tight solver settings of the truth: the simulator defaults with a 4x smaller
// equilibrium tolerance and a 2x longer window, capped at 6000 steps; a truth mesh finer than
// 0.75 mm (make-case --edge below 1.5) also spreads each cord's pull over 2 mm of leaflet
// (cord_insertion_radius_mm; its point insertions do not close there). The default edge is
// the benchmark truths' (point insertions).
SimulationSettings truthSimulationSettings(double truth_edge_mm = 1.25);

// The same settings with half the time step and twice the step cap (the same simulated time):
// dt_ms halved when set, else stiffness_ratio / 4 (the automatic dt goes with its square root).
SimulationSettings halvedTimeStep(SimulationSettings settings);

// The truth closure: `close(settings)`, and when it diverges up to kTruthRetries more times
// with halvedTimeStep each time (a soft lesion in a fine truth mesh can grow a slow
// instability at the default step; bileaflet with soft A2 and P2 tissue, seed 3, default
// edge, diverged at step 3,828 and closes at half the step). `settings` receives the settings
// of the returned run, `retries` how many halvings it took. The returned result still carries
// the error when the last attempt diverged too, or at once for any other error.
constexpr int kTruthRetries = 2;
SimulationResult closeTruthWithRetries(
    const std::function<SimulationResult(const SimulationSettings&)>& close,
    SimulationSettings& settings, int& retries);

// Builds a synthetic case. Throws std::invalid_argument naming the option for bad options
// (unknown preset, edge, planes, noise, dropout) and std::runtime_error when the truth
// simulation fails (divergence). A truth that does not reach equilibrium is kept and flagged
// (truth_result.converged).
SyntheticCase makeSyntheticCase(const SyntheticCaseOptions& options);

// The truth's valve on a mesh of another resolution (edge `edge_mm`), for mesh-convergence
// studies: the same patient anatomy, the same cords (each at its anatomical point, or at the
// nearest vertex when the case was made with attach_at_vertices; the truth's rest lengths and
// PM tips, in mm, not re-derived from the heuristic on the new mesh) and the same lesion
// tissue. Tracings are the truth's; the simulation block is the truth's settings.
ValveCase truthCaseAtEdge(const SyntheticCase& synthetic, double edge_mm);

// The true cords on the case mesh: `case_cords` (the case's cords.json: the same anatomical
// cords as the truth's, in the same order, attached on the case mesh) with the rest lengths,
// provenance and PM tips of `truth_cords` (truth/cords.json). Closed on the case mesh they measure
// the case mesh's discretisation error (experiments/, "true cords on the case mesh"). Not a bound
// on a per-cord fit, which keeps the heuristic's tips and lets the lengths make up for them
// (docs/fitting.md, "Without the mesh error"). Throws std::invalid_argument when the cord or
// tip counts differ.
CordSet trueCordsOnCaseMesh(const CordSet& case_cords, const CordSet& truth_cords);

// Writes the case to `directory` and the truth to `directory`/truth:
//   case.json, open.ply, leaflets.json, annulus_ring.json, annulus_closed.json,
//   tracings.json, cords.json                         (writeCase; case.json last)
//   truth/case/...        the fine valve as a case (true cords, tight settings)
//   truth/cords.json      the true cord set (on truth/case's mesh)
//   truth/closed.ply/.vtk the true closed state with height scalars
//   truth/metrics.json    noise floor (metricsJson) + truth prolapse and simulation summary
//   truth/truth.json      the description: preset, seed, anatomy, pathology, per-cord
//                         attachment, vertices at both resolutions, scales, ruptures
//   truth/cross_sections.svg  one panel per tracing plane
// The truth is written first and case.json last, so an interrupted run leaves no loadable
// case. Every file is written atomically. No file records wall times, so the same options
// give byte-identical files.
void writeSyntheticCase(const std::filesystem::path& directory, const SyntheticCase& synthetic);
// Every file writeSyntheticCase may write, relative to the directory: caseFileNames(), then the
// truth's ("truth/cords.json", ..., "truth/case/case.json", ...).
std::vector<std::string> syntheticCaseFileNames();

// The JSON text of truth/truth.json.
std::string syntheticTruthJson(const SyntheticCase& synthetic);

}  // namespace chordfit
