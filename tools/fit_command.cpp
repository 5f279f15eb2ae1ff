// chordfit fit: fit the cord rest lengths (and optionally the PM tips) of a case to its
// tracings (issue 5). Thin: parse and check the options, call inverse::fitCords, write the
// outputs. The closed mesh and its metrics are written by the simulate command's code path
// (runSimulate on the fitted cords: a full closure from the open state, the same files and
// scalars as `chordfit simulate`), then metrics.json is extended with the fit's keys.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/case_extent.h"
#include "core/case_io.h"
#include "core/cordset_io.h"
#include "core/counted.h"
#include "core/metrics.h"
#include "core/section_figure.h"
#include "core/simulator.h"
#include "inverse/fit_cords.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/fit_report.h"
#include "tools/shell_word.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

namespace {

using inverse::IterationRecord;

constexpr const char* kSeedColour = "#9a9a9a";  // the seed closure in sections.svg

std::string joinNames(const std::vector<std::string>& names) {
  std::string joined;
  for (const std::string& n : names) joined += (joined.empty() ? "" : "|") + n;
  return joined;
}

// Options given to a fit they do not act on: a note each (the run goes on; the user may have
// meant --params scales+tips, or Ceres). After the values are checked, so that a refused
// value is not first noted as unused. On stdout, as the fit's other notes.
void noteOptionsThatDoNotAct(const FitCommandOptions& o) {
  if (o.params != "scales+tips") {
    for (const char* option : {"--tip-box", "--tip-weight", "--fd-tip-step"})
      if (optionGiven(o.given_options, option))
        printNote("fit: %s acts only with --params scales+tips (this fit: --params %s)\n", option,
                  o.params.c_str());
  }
  // The finite differences serve Ceres' Jacobians; NLopt's methods take none, so with them
  // these options reach only the uncertainty's Jacobian, and nothing without it.
  if (o.optimizer != "ceres") {
    for (const char* option : {"--fd-step", "--fd-tip-step", "--fd-warm", "--fd-slack-closures"})
      if (optionGiven(o.given_options, option))
        printNote(
            "fit: %s acts only on %s with --optimizer %s (NLopt's methods take no "
            "derivatives)\n",
            option,
            o.uncertainty
                ? "the steps after the fit (the uncertainty's Jacobian, the locked-cord probe)"
                : "Ceres' Jacobians, so on nothing here (--no-uncertainty)",
            o.optimizer.c_str());
  }
}

// The seed cord set as a message names it: the --seed-cords file, else the case's cords or
// the heuristic's (resolveCords).
std::string seedCordsName(const std::string& seed_cords_file, const ValveCase& valve_case) {
  if (!seed_cords_file.empty()) return seed_cords_file;
  return valve_case.cords ? "the case's cord set" : "the heuristic's cord set";
}

// --- Stage 1: the option values, before any file is read ---

// Whether --out is another directory than the case's; reports it when it is the case's.
bool outputIsNotTheCase(const FitCommandOptions& o) {
  std::error_code same_error;
  if (!std::filesystem::equivalent(o.out_dir, o.case_dir, same_error)) return true;
  std::cerr << "error: fit: --out: " << o.out_dir
            << " is the case directory; the fit's cords.json would replace the case's\n";
  return false;
}

// The parameter mode --params names, or nullopt after reporting an unknown name.
std::optional<inverse::ParameterMode> parameterModeOrReport(const std::string& params) {
  const auto mode = inverse::parseParameterMode(params);
  if (!mode)
    std::cerr << "error: fit: --params: expected scales, groups or scales+tips, got \"" << params
              << "\"\n";
  return mode;
}

// Whether --optimizer and --distance name a known method; reports the first that does not.
bool optimizerAndDistanceKnown(const FitCommandOptions& o) {
  if (!inverse::makeOptimizer(o.optimizer)) {
    std::cerr << "error: fit: --optimizer: expected " << joinNames(inverse::optimizerNames())
              << ", got \"" << o.optimizer << "\"\n";
    return false;
  }
  if (o.distance != "own-leaflet" && o.distance != "surface") {
    std::cerr << "error: fit: --distance: expected own-leaflet or surface, got \"" << o.distance
              << "\"\n";
    return false;
  }
  return true;
}

// Whether --scale-bounds is two numbers 0 < LO < HI; reports it otherwise. The cords' lengths
// at the bounds are checked once the seed is read (scaleBoundsKeepCordsInRange).
bool scaleBoundsWellFormed(const std::vector<double>& scale_bounds) {
  if (scale_bounds.size() == 2 && scale_bounds[0] > 0.0 && scale_bounds[0] < scale_bounds[1])
    return true;
  std::cerr << "error: fit: --scale-bounds: need two numbers 0 < LO < HI, got";
  for (std::size_t i = 0; i < scale_bounds.size(); ++i)
    std::cerr << (i == 0 ? " " : ",") << scale_bounds[i];
  std::cerr << "\n";
  return false;
}

// Whether --section-weight and --tip-weight lie in [0, kMaxWeight]; reports the first that
// does not (NaN included).
bool weightsInRange(const FitCommandOptions& o) {
  // A weight's upper bound: beyond it the other residuals are round-off beside its own, and
  // near 1e154 its squares overflow (--section-weight 1e308 made the cost infinite, and the
  // fit returned its seed with exit 0). The documented weights are 0.01-1.
  constexpr double kMaxWeight = 1000.0;
  for (const auto& [option, weight] :
       {std::pair{"--section-weight", o.section_weight}, std::pair{"--tip-weight", o.tip_weight}}) {
    if (!(weight >= 0.0 && weight <= kMaxWeight)) {
      std::cerr << "error: fit: " << option << ": must be in [0, " << kMaxWeight << "], got "
                << weight << "\n";
      return false;
    }
  }
  return true;
}

// Whether the central-difference steps (--fd-step, --fd-tip-step, both already positive) can
// measure the forward map's slope; reports the first that cannot.
bool finiteDifferenceStepsUsable(const FitCommandOptions& o) {
  if (o.fd_scale_step >= o.scale_bounds[0]) {
    // A central difference at the lower bound closes the scale lower - step: a rest length <= 0.
    std::cerr << "error: fit: --fd-step: " << o.fd_scale_step
              << " is not below the lower scale bound " << o.scale_bounds[0]
              << " (a central difference there would close a scale <= 0)\n";
    return false;
  }
  // Below these a difference measures where the closure stopped, not the map: a 20 mm cord
  // times 1e-6 moves its vertex less than the closure's 1e-4 mm tolerance per step (1e-300
  // gave Jacobian columns of 0 and "0 of 32 cords determined"). Above kMaxTipStepMm a tip's
  // difference is a secant across the ventricle (1e308 mm moved the tips out of the valve and
  // every difference closure diverged).
  constexpr double kMinScaleStep = 1e-6, kMinTipStepMm = 1e-4, kMaxTipStepMm = 5.0;
  if (o.fd_scale_step < kMinScaleStep) {
    std::cerr << "error: fit: --fd-step: " << o.fd_scale_step << " is below " << kMinScaleStep
              << ", where a central difference measures the closure's stopping tolerance, not "
                 "the forward map (the default 0.01 was chosen from the map's noise: "
                 "docs/fitting.md)\n";
    return false;
  }
  if (!(o.fd_tip_step_mm >= kMinTipStepMm && o.fd_tip_step_mm <= kMaxTipStepMm)) {
    std::cerr << "error: fit: --fd-tip-step: must be in [" << kMinTipStepMm << ", " << kMaxTipStepMm
              << "] mm, got " << o.fd_tip_step_mm
              << " (smaller measures the closure's stopping tolerance, larger is a secant, not "
                 "a slope; the default is 0.1 mm)\n";
    return false;
  }
  return true;
}

// A note when --fd-step is usable but wide: the run goes on.
void noteWideScaleStep(const FitCommandOptions& o) {
  if (o.fd_scale_step > 0.1)
    printNote(
        "fit: --fd-step %g is a central difference over %g..%g of each scale: a "
        "secant across the map's kinks, not its slope (the default 0.01 was chosen from "
        "the map's noise, docs/fitting.md)\n",
        o.fd_scale_step, 1.0 - o.fd_scale_step, 1.0 + o.fd_scale_step);
}

// Stage 1. The parameter mode of the fit when every option value that needs no input file is
// acceptable; otherwise nullopt, after reporting the first refused value in the order below.
std::optional<inverse::ParameterMode> checkOptionValues(const FitCommandOptions& o) {
  if (!outputIsNotTheCase(o)) return std::nullopt;
  const auto mode = parameterModeOrReport(o.params);
  if (!mode || !optimizerAndDistanceKnown(o) || !scaleBoundsWellFormed(o.scale_bounds) ||
      !weightsInRange(o))
    return std::nullopt;
  // --threads is checked where it is read, with every command's (main.cpp).
  if (!optionsArePositive("fit",
                          {{"--max-sims", o.max_sims},
                           {"--tip-box", o.tip_box_mm},
                           {"--fd-step", o.fd_scale_step},
                           {"--fd-tip-step", o.fd_tip_step_mm}},
                          "a positive number"))
    return std::nullopt;
  if (!finiteDifferenceStepsUsable(o)) return std::nullopt;
  noteWideScaleStep(o);
  return mode;
}

// --- Stage 2: the case, the seed cords and the settings, checked against the options ---

struct FitInputs {
  ValveCase valve_case;
  CordSet seed;
  SimulationSettings settings;
};

// The case at `case_dir` when it loads and has tracings (a note on duplicate tracings goes to
// stderr); otherwise nullopt, reported.
std::optional<ValveCase> caseWithTracingsOrReport(const std::string& case_dir) {
  auto valve_case = loadCaseOrReport(case_dir);
  if (!valve_case) return std::nullopt;
  if (valve_case->tracings.empty()) {
    // The file and field as every case problem names them ("DIR/case.json: tracings: ...").
    std::cerr << "error: " << (std::filesystem::path(case_dir) / "case.json").string()
              << ": tracings: the fit needs tracings (a case without them can be simulated, "
                 "not fitted; docs/case-format.md, \"Tracings\")\n";
    return std::nullopt;
  }
  printLinesToStderr(duplicateTracingsNote(*valve_case));
  return valve_case;
}

// Whether --tip-box keeps a moved tip within the case's reach; reports it otherwise. True for
// other modes than scales+tips, where the box does not act.
bool tipBoxWithinReach(const FitCommandOptions& o, inverse::ParameterMode mode,
                       const ValveCase& valve_case) {
  // A tip moved by the box on all three axes goes sqrt(3) box: beyond the case's reach, where
  // no case file may put a tip (1e308 gave crs2 an infinite domain and sent bobyqa's first
  // steps out of the ventricle). Only where it acts: with other --params it is noted, not used.
  const double reach = valveReachMm(valve_case.mesh.V);
  if (mode != inverse::ParameterMode::kScalesAndTips || std::sqrt(3.0) * o.tip_box_mm <= reach)
    return true;
  char most[32];
  std::snprintf(most, sizeof most, "%.1f", reach / std::sqrt(3.0) - 0.05);
  std::cerr << "error: fit: --tip-box: " << o.tip_box_mm << " mm reaches beyond this case: at most "
            << most << " mm (a tip moved by it on all three axes goes sqrt(3) times as far, and "
            << "tips stay within " << reach << " mm of the valve mesh, the larger of 50 mm and "
            << "its span; the default is 8 mm)\n";
  return false;
}

// The seed cord set (--seed-cords, else the case's, else the heuristic's) when it has cords;
// otherwise nullopt, reported.
std::optional<CordSet> seedWithCordsOrReport(const FitCommandOptions& o,
                                             const ValveCase& valve_case) {
  auto seed = resolveCords(valve_case, o.seed_cords_file);
  if (!seed) return std::nullopt;
  if (seed->cords.empty()) {
    std::cerr << "error: fit: "
              << noCordsProblem(valve_case, o.case_dir, o.seed_cords_file, "--seed-cords")
              << ": nothing to fit\n";
    return std::nullopt;
  }
  return seed;
}

// Whether every free cord stays within the cord-set readers' lengths
// [kMinCordRestLengthMm, kMaxCordRestLengthMm] at both scale bounds, as each cord's own scale
// moves it; reports the first that does not. For --params groups see also
// groupBoundsKeepCordsInRange.
bool scaleBoundsKeepCordsInRange(const FitCommandOptions& o, inverse::ParameterMode mode,
                                 const ValveCase& valve_case, const CordSet& seed) {
  // A scale at either bound must leave a cord set the readers take (cords.json is read
  // back for the fitted closure); found after the fit, it would cost the whole run.
  // Per cord (scales, scales+tips) a scale multiplies the seed rest length, whatever the cord's
  // present length (a manual 0.045 of it starts clamped): check the lengths the bounds reach.
  const bool per_cord = mode != inverse::ParameterMode::kGroups;
  // The cord named as the user can find it: its index in the seed file (or the case's cords).
  const std::string seed_name = seedCordsName(o.seed_cords_file, valve_case);
  for (std::size_t c = 0; c < seed.cords.size(); ++c) {
    const Cord& cord = seed.cords[c];
    if (cord.locked) continue;
    const double length =
        per_cord ? cord.seed_rest_length : std::max(cord.seed_rest_length, cord.rest_length);
    const double reach = length * o.scale_bounds[1];
    if (reach > kMaxCordRestLengthMm) {
      std::cerr << "error: fit: --scale-bounds: the upper bound " << o.scale_bounds[1]
                << " lets cord " << c << " of " << seed_name << " (" << length << " mm) reach "
                << reach << " mm; a cord set holds at most " << kMaxCordRestLengthMm << " mm\n";
      return false;
    }
    const double shortest =
        per_cord ? cord.seed_rest_length : std::min(cord.seed_rest_length, cord.rest_length);
    const double shrunk = shortest * o.scale_bounds[0];
    if (shrunk < kMinCordRestLengthMm) {
      std::cerr << "error: fit: --scale-bounds: the lower bound " << o.scale_bounds[0]
                << " lets cord " << c << " of " << seed_name << " (" << shortest
                << " mm) shrink to " << shrunk << " mm; a cord set holds at least "
                << kMinCordRestLengthMm << " mm\n";
      return false;
    }
  }
  return true;
}

// --params groups: whether every free cord stays within the readers' lengths at its group
// factor's bounds; reports the first that does not.
bool groupBoundsKeepCordsInRange(const FitCommandOptions& o, const ValveCase& valve_case,
                                 const CordSet& seed) {
  // A group factor's bounds keep the group's mean scale within --scale-bounds, so a cord
  // above its group's mean goes further than scaleBoundsKeepCordsInRange assumes: take the lengths
  // at the factors' bounds themselves.
  inverse::ParameterBounds bounds;
  bounds.scale_lower = o.scale_bounds[0];
  bounds.scale_upper = o.scale_bounds[1];
  const inverse::FitParameterization groups(valve_case, seed, inverse::ParameterMode::kGroups,
                                            bounds);
  const CordSet longest = groups.apply(groups.upper());
  const CordSet shortest = groups.apply(groups.lower());
  const std::vector<std::string> names = inverse::cordGroups(valve_case, seed);
  const std::string seed_name = seedCordsName(o.seed_cords_file, valve_case);
  for (std::size_t c = 0; c < seed.cords.size(); ++c) {
    if (seed.cords[c].locked) continue;
    const double reach = longest.cords[c].rest_length, shrunk = shortest.cords[c].rest_length;
    if (reach <= kMaxCordRestLengthMm && shrunk >= kMinCordRestLengthMm) continue;
    const bool too_long = reach > kMaxCordRestLengthMm;
    std::cerr << "error: fit: --scale-bounds: with --params groups the "
              << (too_long ? "upper" : "lower") << " bound " << o.scale_bounds[too_long ? 1 : 0]
              << " lets cord " << c << " of " << seed_name << " (group " << names[c] << ", "
              << seed.cords[c].rest_length << " mm) " << (too_long ? "reach " : "shrink to ")
              << (too_long ? reach : shrunk)
              << " mm (the group factor's bound keeps the group's mean scale within it, not "
                 "each cord's); a cord set holds "
              << kMinCordRestLengthMm << " to " << kMaxCordRestLengthMm << " mm\n";
    return false;
  }
  return true;
}

// Stage 2. The case, the seed and the closure settings when they load and suit the options
// (`mode` from checkOptionValues); otherwise nullopt, after reporting the first problem.
std::optional<FitInputs> loadFitInputs(const FitCommandOptions& o, inverse::ParameterMode mode) {
  auto valve_case = caseWithTracingsOrReport(o.case_dir);
  if (!valve_case || !tipBoxWithinReach(o, mode, *valve_case)) return std::nullopt;
  auto seed = seedWithCordsOrReport(o, *valve_case);
  if (!seed || !scaleBoundsKeepCordsInRange(o, mode, *valve_case, *seed)) return std::nullopt;
  if (mode == inverse::ParameterMode::kGroups &&
      !groupBoundsKeepCordsInRange(o, *valve_case, *seed))
    return std::nullopt;
  // Writes the --set overrides into the case's settings too, for the metrics and figures that
  // read them later.
  const auto settings = caseSettingsOrReport(*valve_case, o.case_dir, SettingsUse::kClose, "fit",
                                             o.settings_overrides);
  if (!settings) return std::nullopt;
  return FitInputs{std::move(*valve_case), std::move(*seed), *settings};
}

// --- Stages 3 and 4: the fit's options and its progress lines ---

// Stage 3. The options of inverse::fitCords as the command's options ask for them, without
// progress callbacks (reportProgressOnStdout adds them).
inverse::FitOptions fitOptionsFor(const FitCommandOptions& o, inverse::ParameterMode mode) {
  inverse::FitOptions options;
  options.mode = mode;
  options.bounds.scale_lower = o.scale_bounds[0];
  options.bounds.scale_upper = o.scale_bounds[1];
  options.bounds.tip_box_mm = o.tip_box_mm;
  options.prefit.enabled = o.prefit;
  options.segment_prefit.enabled = o.prefit;
  options.tissue_prefit.enabled = o.tissue_prefit;
  options.tissue_retry = o.tissue_retry;
  options.slack_release.enabled = o.slack_release;
  options.optimizer = o.optimizer;
  options.max_sims = o.max_sims;
  options.finite_difference.threads = o.threads;
  options.finite_difference.scale_step = o.fd_scale_step;
  options.finite_difference.tip_step_mm = o.fd_tip_step_mm;
  options.finite_difference.warm_start = o.fd_warm_start;
  options.finite_difference.skip_slack = !o.fd_slack_closures;
  options.residual.own_leaflet = o.distance == "own-leaflet";
  options.residual.section_weight = o.section_weight;
  options.residual.weights.tip_per_mm = o.tip_weight;
  options.uncertainty = o.uncertainty;
  options.probe_locked = o.uncertainty;  // the after-fit diagnostics go together
  return options;
}

// One line of an optimisation's progress on stdout.
void printIterationLine(const IterationRecord& r) {
  // Columns aligned within each optimisation: the stage names of one ("segments" the
  // longest) and of the tissue retry's ("retry release" the longest).
  const int stage_width = r.stage.rfind("retry ", 0) == 0 ? 13 : 8;
  std::printf("%-*s iter %4d  cost %10.4f  best %10.4f  mean %7.4f mm  sims %4d  %7.1f s\n",
              stage_width, r.stage.c_str(), r.iteration, r.cost, r.best_cost, r.mean_deviation_mm,
              r.forward_sims, r.elapsed_s);
  std::fflush(stdout);
}

// Stage 4 (not with --quiet). Prints what is about to be fitted, and sets `options`' callbacks
// to print each stage and iteration on stdout as the fit goes.
void reportProgressOnStdout(const FitCommandOptions& o, const FitInputs& inputs,
                            inverse::FitOptions& options) {
  std::printf("fitting %s: %s, %s, %s, at most %s, %s\n", inputs.valve_case.name.c_str(),
              counted(inputs.seed.cords.size(), "cord").c_str(), o.params.c_str(),
              o.optimizer.c_str(), counted(o.max_sims, "forward run").c_str(),
              counted(o.threads, "thread").c_str());
  const std::string skip_reason = inverse::prefitSkipReason(inputs.seed);
  if (o.prefit && !skip_reason.empty()) std::printf("pre-fits skipped: %s\n", skip_reason.c_str());
  options.on_stage = [](const std::string& line) {
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  };
  options.on_iteration = printIterationLine;
}

// Stage 5's failure: reports why the fit did not run to its end and returns the exit code.
int reportFitFailure(const FitCommandOptions& o, const inverse::FitOutcome& fit) {
  std::cerr << "error: " << o.case_dir << ": " << fit.error << "\n";
  return fit.error_is_input ? kExitBadInput : kExitSimulationFailed;
}

// --- Stage 6: the output files ---

// What writeFitOutputs leaves for the summary.
struct WrittenFit {
  int exit_code = kExitOk;  // otherwise the failure was reported and nothing was published
  StagedOutput::Published published;
  ValveMetrics seed_metrics, fit_metrics;
};

// `chordfit simulate`'s options that close the fitted cords (on the fitted tissue, if any)
// into `out`, the staging directory.
SimulateOptions fittedClosureSimulation(const FitCommandOptions& o, const inverse::FitOutcome& fit,
                                        const std::filesystem::path& out) {
  SimulateOptions simulate;
  simulate.case_dir = o.case_dir;
  simulate.cords_file = (out / "cords.json").string();
  if (fit.tissue.size() > 0) simulate.tissue_file = (out / "tissue.json").string();
  simulate.out_dir = out.string();
  simulate.threads = o.threads;
  simulate.settings_overrides = o.settings_overrides;
  simulate.quiet = true;
  // sections.svg is writeFitFigures', with the seed closure beside the fitted one; the files
  // are listed once published (printFitSummary).
  simulate.sections = false;
  simulate.report_files = false;
  return simulate;
}

// Writes cords.json (and tissue.json) into `out`, then the fitted closure there as `chordfit
// simulate` writes it: closed.ply, closed.vtk and metrics.json. Returns runSimulate's exit
// code (its failure reported).
int writeFittedCordsAndClosure(const FitCommandOptions& o, const ValveCase& valve_case,
                               const inverse::FitOutcome& fit, const std::filesystem::path& out) {
  writeCordSet(out / "cords.json", fit.fitted, &valve_case.mesh);
  // The tissue the cords were fitted on, when the tissue pre-fit changed it; the closure
  // written next uses it too.
  if (fit.tissue.size() > 0) writeTissueFile(out / "tissue.json", fit.tissue);
  std::printf("fitted cords: full closure from the open state\n");
  return runSimulate(fittedClosureSimulation(o, fit, out));
}

// metrics.json's "uncertainty" (docs/outputs.md): the Jacobian's cost, and its result or why
// there is none.
nlohmann::json uncertaintyMetrics(const inverse::FitOutcome& fit) {
  nlohmann::json u = {{"jacobian_sims", fit.uncertainty.jacobian_sims},
                      {"unsettled_sims", fit.uncertainty.unsettled_sims},
                      {"seconds", fit.uncertainty_seconds}};
  if (fit.uncertainty.ok()) {
    u["residual_sd_mm"] = fit.uncertainty.sigma_mm;
    u["correlation_time"] = fit.uncertainty.correlation_time;
    u["identified_cords"] = identifiedCords(fit);
    u["free_cords"] = freeCords(fit);
  } else {
    u["error"] = fit.uncertainty.error.empty() ? "no free parameters" : fit.uncertainty.error;
  }
  return u;
}

// Adds the pre-fits' keys to metrics.json: whether each ran and what it changed.
void addPrefitMetrics(nlohmann::json& metrics, const inverse::FitOutcome& fit) {
  // Whether the cord pre-fits ran (options.prefit says only that they were asked for), and
  // why not when they were skipped.
  metrics["prefit_ran"] = fit.prefit_ran;
  metrics["prefit_kind_ran"] = fit.prefit_kind_stage == inverse::KindStage::kRan;
  metrics["segment_prefit_ran"] = fit.segment_prefit_ran;
  metrics["tissue_prefit_ran"] = fit.tissue_prefit_ran;
  if (!fit.prefit_skipped.empty()) metrics["prefit_skipped"] = fit.prefit_skipped;
  metrics["prefit_factor"] = fit.prefit_factor;
  metrics["prefit_primary_factor"] = fit.prefit_primary_factor;
  metrics["prefit_secondary_factor"] = fit.prefit_secondary_factor;
  metrics["segment_prefit"] = fit.segment_prefit_changes;
  metrics["tissue_prefit"] = fit.tissue_prefit_changes;
  metrics["tissue_retry"] = tissueRetryJson(fit);
  const inverse::SlackReleaseOutcome& release = fit.slack_release;
  metrics["slack_release"] = {{"proposed_cords", release.proposal.cords.size()},
                              {"kept", release.kept},
                              {"primary_reference", release.proposal.primary_reference},
                              {"secondary_reference", release.proposal.secondary_reference}};
}

// Adds the options the fit ran with to metrics.json.
void addRunOptionMetrics(nlohmann::json& metrics, const FitCommandOptions& o) {
  metrics["distance"] = o.distance;  // the data residual the fit minimised
  metrics["section_weight"] = o.section_weight;
  metrics["tip_weight"] = o.tip_weight;
  metrics["scale_bounds"] = o.scale_bounds;
  // How the fit was run, so that two results can be told apart by their files alone.
  metrics["options"] = {{"prefit", o.prefit},
                        {"tissue_prefit", o.tissue_prefit},
                        {"tissue_retry", o.tissue_retry},
                        {"slack_release", o.slack_release},
                        {"tip_box_mm", o.tip_box_mm},
                        {"fd_step", o.fd_scale_step},
                        {"fd_tip_step_mm", o.fd_tip_step_mm},
                        {"fd_warm", o.fd_warm_start},
                        {"fd_slack_closures", o.fd_slack_closures},
                        {"uncertainty", o.uncertainty}};
}

// Adds the fit's keys (docs/outputs.md) to `metrics`, the closure's metrics.json as simulate
// wrote it.
void addFitMetrics(nlohmann::json& metrics, const FitCommandOptions& o, const ValveCase& valve_case,
                   const inverse::FitOutcome& fit) {
  metrics["optimizer"] = o.optimizer;
  metrics["params"] = o.params;
  metrics["parameters"] = fit.x.size();
  metrics["forward_sims"] = fit.forward_sims + 1;  // + the closure just written
  metrics["unsettled_sims"] = fit.unsettled_sims;  // of the fit's runs (not the one written)
  metrics["fit_seconds"] = fit.seconds;
  metrics["initial_mean_mm"] = fit.seed_evaluation.mean_deviation_mm;
  metrics["initial_cost"] = fit.seed_evaluation.cost;
  metrics["final_cost"] = fit.final_evaluation.cost;
  addPrefitMetrics(metrics, fit);
  addRunOptionMetrics(metrics, o);
  // With --fd-warm: whether Ceres gave warm-started differences up for full closures.
  if (o.fd_warm_start) metrics["fd_switched_to_full_closures"] = fit.switched_to_full_closures;
  if (o.uncertainty) metrics["uncertainty"] = uncertaintyMetrics(fit);
  if (!fit.locked_probes.cords.empty())
    metrics["locked_cord_probe"] = lockedProbeJson(valve_case, fit);
  metrics["slack_cords"] = slackCords(fit);
  metrics["termination"] = fit.termination;
  metrics["threads"] = o.threads;
}

// Rewrites `out`/metrics.json with the fit's keys added. Returns false, reported, when the
// file cannot be read back.
bool extendMetricsFile(const std::filesystem::path& out, const FitCommandOptions& o,
                       const ValveCase& valve_case, const inverse::FitOutcome& fit) {
  std::string metrics_text;
  if (!readWholeFile(out / "metrics.json", metrics_text)) {
    std::cerr << "error: fit: cannot read back " << (out / "metrics.json").string() << "\n";
    return false;
  }
  nlohmann::json metrics = nlohmann::json::parse(metrics_text);
  addFitMetrics(metrics, o, valve_case, fit);
  writeFileAtomically(out / "metrics.json", metrics.dump(2) + "\n");
  return true;
}

// Writes into `out` what the fit adds to the closure's files: convergence.csv and .svg,
// uncertainty.csv (when computed), report.md and sections.svg (the seed closure beside the
// fitted one).
void writeFitFigures(const std::filesystem::path& out, const FitCommandOptions& o,
                     const ValveCase& valve_case, const inverse::FitOutcome& fit,
                     const ValveMetrics& seed_metrics, const ValveMetrics& fit_metrics) {
  writeFileAtomically(out / "convergence.csv", convergenceCsv(fit.history));
  if (fit.uncertainty.ok()) writeFileAtomically(out / "uncertainty.csv", uncertaintyCsv(fit));
  // Figures name the method that made the result: the pre-fits' when the optimiser took no step.
  const std::string no_step = optimiserNoStep(fit, o.optimizer);
  const std::string method = no_step.empty() ? o.optimizer : no_step;
  writeFileAtomically(out / "convergence.svg", convergenceSvg(fit.history, method));
  writeFileAtomically(out / "report.md", fitReport(valve_case, o, fit, seed_metrics, fit_metrics));
  writeFileAtomically(
      out / "sections.svg",
      caseSectionFigureSvg(valve_case,
                           {{"seed closure", fit.seed_evaluation.closed_V, kSeedColour, true, 1.4},
                            {"fitted closure", fit.final_evaluation.closed_V, "", false, 2.0}},
                           {valve_case.name + ": seed and fitted closures against the tracings (" +
                            method + ", " + o.params + ")"}));
}

// Stage 6. Writes every output file into a staging directory and publishes them into --out
// together (staged_output.h). On failure (reported) the exit code is set and --out is left
// as it was; exceptions (a failed write) propagate, as from every command, to main.
WrittenFit writeFitOutputs(const FitCommandOptions& o, const ValveCase& valve_case,
                           const inverse::FitOutcome& fit) {
  WrittenFit written;
  StagedOutput staged(o.out_dir, fitOutputFiles(), {}, "fit");
  const std::filesystem::path& out = staged.dir();
  written.exit_code = writeFittedCordsAndClosure(o, valve_case, fit, out);
  if (written.exit_code != kExitOk) return written;
  written.seed_metrics = computeMetrics(valve_case, fit.seed_evaluation.closed_V);
  written.fit_metrics = computeMetrics(valve_case, fit.final_evaluation.closed_V);
  if (!extendMetricsFile(out, o, valve_case, fit)) {
    written.exit_code = kExitFailure;
    return written;
  }
  writeFitFigures(out, o, valve_case, fit, written.seed_metrics, written.fit_metrics);
  written.published = staged.publish();
  return written;
}

// --- Stage 7: the summary on the terminal ---

// "fit: ceres after N forward runs, T s (termination)", or the pre-fits' line when the
// optimiser took no step.
void printFitEndLine(const FitCommandOptions& o, const inverse::FitOutcome& fit) {
  const std::string no_step = optimiserNoStep(fit, o.optimizer);
  if (no_step.empty())
    std::printf("fit: %s after %s, %.1f s (%s)\n", o.optimizer.c_str(),
                counted(fit.forward_sims, "forward run").c_str(), fit.seconds,
                fit.termination.c_str());
  else  // "ceres after 57 forward runs" credited it with the pre-fits' work
    std::printf("fit: %s (%s), %.1f s (%s)\n", counted(fit.forward_sims, "forward run").c_str(),
                no_step.c_str(), fit.seconds, fit.termination.c_str());
}

// A note when a derivative-free local NLopt method stopped on its tolerance with much of the
// budget left.
void noteEarlyDerivativeFreeStop(const FitCommandOptions& o, const inverse::FitOutcome& fit) {
  // NLopt's local methods stop on a relative cost change between evaluations, which a
  // simulator's map can meet far from a minimum (bobyqa on the quick start's case: AvgD
  // 0.73 mm after 137 of 400 closures, where ceres reaches 0.40; after 137 of 150 too, two
  // evaluations of the same cost, so the note does not wait for half the budget).
  const auto driver = inverse::makeOptimizer(o.optimizer);
  const int unused = o.max_sims - fit.forward_sims;
  if (driver && driver->localDerivativeFree() && fit.termination.rfind("converged", 0) == 0 &&
      unused >= std::max(5, o.max_sims / 20)) {
    printNote(
        "%s stopped on its tolerance with %d of --max-sims %d %s unused; a "
        "derivative-free local method can stop early on a simulator's map (compare with "
        "--optimizer ceres, the default)\n",
        o.optimizer.c_str(), unused, o.max_sims, nounFor(o.max_sims, "closure").c_str());
  }
}

// The uncertainty's summary line, or a note on why it could not be computed.
void printUncertaintySummary(const FitCommandOptions& o, const inverse::FitOutcome& fit) {
  if (fit.uncertainty.ok()) {
    std::printf(
        "uncertainty: %d of %d free cords determined to better than 3 %% (residual SD %.2f mm, "
        "correlated over %.1f points; %s, %.1f s; report.md, uncertainty.csv)\n",
        identifiedCords(fit), freeCords(fit), fit.uncertainty.sigma_mm,
        fit.uncertainty.correlation_time,
        extraClosures(fit.uncertainty.jacobian_sims, fit.uncertainty.unsettled_sims).c_str(),
        fit.uncertainty_seconds);
  } else if (o.uncertainty && !fit.uncertainty.error.empty()) {
    printNote("%s\n", fit.uncertainty.error.c_str());
  }
}

// When the fitted closure is on softer tissue, the simulate command that reproduces it.
void printSofterTissueReproduction(const FitCommandOptions& o, const inverse::FitOutcome& fit) {
  if (fit.tissue.size() == 0) return;
  // compare and simulate close cords on the case's own tissue unless told otherwise.
  const std::filesystem::path out_dir(o.out_dir);
  std::cout << "the fitted closure is on softer tissue ("
            << (fit.tissue_retry.kept ? "tissue retry" : "tissue pre-fit")
            << "): chordfit simulate " << shellWord(o.case_dir) << " --cords "
            << shellWord((out_dir / "cords.json").string()) << " --tissue "
            << shellWord((out_dir / "tissue.json").string())
            << " reproduces it (compare: --tissues)\n";
}

// Stage 7. The fit's summary: how it ended, notes on the run, the seed and fitted closures
// side by side (Table 1), advice, and the files written (stdout; notes on stderr).
void printFitSummary(const FitCommandOptions& o, const ValveCase& valve_case,
                     const inverse::FitOutcome& fit, const WrittenFit& written) {
  printFitEndLine(o, fit);
  noteEarlyDerivativeFreeStop(o, fit);
  if (fit.unsettled_sims > 0) {
    printNote(
        "%d of the %d forward runs reached the step cap without settling (their state is "
        "the mean over the last steps; docs/performance.md)\n",
        fit.unsettled_sims, fit.forward_sims);
  }
  printUncertaintySummary(o, fit);
  if (const std::string why = tissuePrefitNotRun(fit, o); !why.empty())
    printNote("--tissue-prefit %s (the cords were fitted on the case's tissue)\n",
              why.c_str());  // report.md said so; the terminal did not
  std::cout << tipOffsetsLine(fit);
  if (fit.tissue_retry.ran || !fit.tissue_retry.skipped.empty())
    std::cout << "tissue retry: " << tissueRetryLine(fit, o) << "\n";
  printLockedProbeSummary(valve_case, o, fit);
  std::cout << table1Header("Cord set") << table1Row("seed", written.seed_metrics)
            << table1Row("fit", written.fit_metrics);
  if (const std::string note = worseThanSeedNote(fit); !note.empty()) printNote("%s", note.c_str());
  if (const std::string hint = missedProlapseHint(valve_case, o, fit, written.fit_metrics);
      !hint.empty())
    printNote("%s", hint.c_str());
  printSofterTissueReproduction(o, fit);
  std::cout << wroteLine(o.out_dir, written.published) << "\n";
}

}  // namespace

// The fit as a sequence of stages, each of which reports its own failure.
int runFit(const FitCommandOptions& o) {
  const auto mode = checkOptionValues(o);
  if (!mode) return kExitBadInput;
  const auto inputs = loadFitInputs(o, *mode);
  if (!inputs) return kExitBadInput;
  noteOptionsThatDoNotAct(o);  // every input checked

  inverse::FitOptions options = fitOptionsFor(o, *mode);
  if (!o.quiet) reportProgressOnStdout(o, *inputs, options);
  const inverse::FitOutcome fit =
      inverse::fitCords(inputs->valve_case, inputs->seed, inputs->settings, options);
  if (!fit.ok()) return reportFitFailure(o, fit);

  const WrittenFit written = writeFitOutputs(o, inputs->valve_case, fit);
  if (written.exit_code != kExitOk) return written.exit_code;
  printFitSummary(o, inputs->valve_case, fit, written);
  return kExitOk;
}

std::vector<std::string> fitOutputFiles() {
  // tissue.json only when the tissue pre-fit changed the tissue, uncertainty.csv only when
  // the uncertainty could be computed.
  std::vector<std::string> files = {"cords.json", "tissue.json"};
  for (const std::string& name : closureOutputFiles(false)) files.push_back(name);
  files.insert(files.end(), {"convergence.csv", "convergence.svg", "uncertainty.csv",
                             "sections.svg", "report.md"});
  return files;
}

}  // namespace chordfit::cli
