#include "tools/fit_inputs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/case_extent.h"
#include "core/case_io.h"
#include "core/cordset_io.h"
#include "core/simulator.h"
#include "inverse/fit_cords.h"
#include "tools/command_support.h"
#include "tools/commands.h"

namespace chordfit::cli {

namespace {

std::string joinNames(const std::vector<std::string>& names) {
  std::string joined;
  for (const std::string& n : names) joined += (joined.empty() ? "" : "|") + n;
  return joined;
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

}  // namespace

// Stage 1 (fit_inputs.h); the checks in the order they are reported.
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

namespace {

// --- Stage 2: the case, the seed cords and the settings, checked against the options ---

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
  auto seed = resolveCords(valve_case, o.seed_cords_file, "fit: --seed-cords");
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

}  // namespace

// Stage 2 (fit_inputs.h).
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

}  // namespace chordfit::cli
