// calibrate_cohort: closes a cohort preset's truths, optionally with changed preset values, and
// prints what the calibration of experiments/README.md ("Calibration") reads: the mesh and
// tracing prolapse, the highest point of each Carpentier segment above the closed annulus, the
// orifice coverage (orifice_coverage.h) and the truth closure's convergence. No files are
// written. Arguments are parsed by hand (CLI11 is confined to tools/main.cpp for build time).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/cohort_presets.h"
#include "core/synthetic_case.h"
#include "experiments/tool_support.h"

namespace {

using namespace chordfit;
using tool_support::parseNumber;
using tool_support::parsePositiveInteger;

constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;
constexpr int kExitUsage = 2;

const char* kUsage = R"(usage: calibrate_cohort PRESET [options] [KEY=VALUE ...]

Closes the truths of PRESET (chordfit make-case --list) for each seed, with the truth
settings of make-case, and prints per seed: mesh prolapse, tracing prolapse, the highest point
of each segment (mm above the closed annulus, open-state localisation), the fraction of the
orifice the leaflets cover seen en face, convergence.

options:
  --seeds LIST       patient seeds, comma-separated (default 1,2,3)
  --edge MM          case mesh edge; the truth mesh is half of it (default 3)
  --max-steps N      truth step cap (default that of make-case, 6000)
  --ramp MS          truth pressure ramp (default that of make-case, 6 ms)
  --insertion-radius MM   truth cord insertion spread (SimulationSettings::
                     cord_insertion_radius_mm; default that of make-case)

KEY=VALUE changes the preset before the cases are made:
  normal=S           normal cord scale (kNormalCordScale)
  secondary=F        secondary cord factor (kSecondaryCordFactor)
  A1=S ... P3=S      peak scale of a segment's cords (0 = normal)
  width=W            pathology profile width (fraction of the leaflet)
  lesion=F           lesion tissue stiffness factor (1 = none)
  lesion_segments=A2,P2   segments with lesion tissue (empty = every pathological one)
  anterior_height=MM, posterior_height=MM (P2), posterior_side_height=MM (P1, P3),
  commissural_height=MM, saddle=MM (open; the closed saddle keeps its ratio),
  indentation=F      anatomy
  closed_contraction=F, closed_saddle=MM   the closed annulus (in-plane ratio to the open
                     one, and the closed saddle height)
)";

int usageError(const std::string& message) {
  std::cerr << "calibrate_cohort: error: " << message << "\n(calibrate_cohort --help)\n";
  return kExitUsage;
}

// Applies KEY=VALUE to the preset; an empty string when it worked, else the problem.
std::string applySetting(const std::string& setting, CohortPreset& preset) {
  const std::size_t eq = setting.find('=');
  if (eq == std::string::npos) return "expected KEY=VALUE, got \"" + setting + "\"";
  const std::string key = setting.substr(0, eq), text = setting.substr(eq + 1);
  if (key == "lesion_segments") {
    preset.lesion_segments = {false, false, false, false, false, false};
    std::istringstream in(text);
    for (std::string name; std::getline(in, name, ',');) {
      const int segment = mitralSegmentId(name);
      if (segment < 0) return "lesion_segments: \"" + name + "\" is not A1..P3";
      preset.lesion_segments[segment] = true;
    }
    return "";
  }
  double value = 0.0;
  if (!parseNumber(text, value)) return key + ": expected a number, got \"" + text + "\"";
  ValveParameters& a = preset.anatomy;
  if (key == "normal") {
    preset.normal_cord_scale = value;
  } else if (key == "secondary") {
    preset.secondary_cord_factor = value;
  } else if (mitralSegmentId(key) >= 0) {
    preset.segment_scale[mitralSegmentId(key)] = value;
  } else if (key == "width") {
    preset.pathology_width = value;
  } else if (key == "lesion") {
    preset.lesion_stiffness = value;
  } else if (key == "anterior_height") {
    a.anterior_height_mm = value;
  } else if (key == "posterior_height") {
    a.posterior_height_mm = value;
  } else if (key == "posterior_side_height") {
    a.posterior_side_height_mm = value;
  } else if (key == "commissural_height") {
    a.commissural_height_mm = value;
  } else if (key == "saddle") {
    a.closed_saddle_height_mm *= value / a.saddle_height_mm;
    a.saddle_height_mm = value;
  } else if (key == "indentation") {
    a.indentation_depth = value;
  } else if (key == "closed_contraction") {
    a.closed_contraction = value;
  } else if (key == "closed_saddle") {
    a.closed_saddle_height_mm = value;
  } else {
    return "unknown key \"" + key + "\"";
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  int exit_code = kExitOk;
  const CohortPreset* named =
      tool_support::presetArgument(argc, argv, kUsage, usageError, exit_code);
  if (!named) return exit_code;
  CohortPreset preset = *named;  // a copy: KEY=VALUE arguments change it
  std::vector<std::uint64_t> seeds = {1, 2, 3};
  double edge = 3.0;
  SimulationSettings settings = truthSimulationSettings();
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    double value = 0.0;
    if (arg == "--seeds") {
      if (!has_value) return usageError("--seeds: expected a list");
      std::string bad;
      if (!tool_support::parseSeedList(argv[++i], seeds, bad)) {
        return usageError("--seeds: expected positive integers, got \"" + bad + "\"");
      }
    } else if (arg == "--edge") {
      if (!has_value || !parseNumber(argv[++i], edge) || !(edge > 0.0)) {
        return usageError("--edge: expected a positive length in mm");
      }
    } else if (arg == "--max-steps") {
      if (!has_value || !parsePositiveInteger(argv[++i], value)) {
        return usageError("--max-steps: expected a positive integer");
      }
      settings.max_steps = static_cast<int>(value);
    } else if (arg == "--ramp") {
      if (!has_value || !parseNumber(argv[++i], value) || !(value > 0.0)) {
        return usageError("--ramp: expected a positive duration in ms");
      }
      settings.ramp_ms = value;
    } else if (arg == "--insertion-radius") {
      if (!has_value || !parseNumber(argv[++i], value) || !(value >= 0.0)) {
        return usageError("--insertion-radius: expected a length >= 0 in mm");
      }
      settings.cord_insertion_radius_mm = value;
    } else if (const std::string problem = applySetting(arg, preset); !problem.empty()) {
      return usageError(problem);
    }
  }
  std::printf(
      "| Seed | Mesh prolapse | Tracing prolapse | A1 | A2 | A3 | P1 | P2 | P3 | Orifice covered "
      "| Converged (steps) | Time-step halvings |\n"
      "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|\n");
  for (const std::uint64_t seed : seeds) {
    SyntheticCaseOptions options;
    options.preset = preset.name;
    options.custom_preset = preset;
    options.seed = seed;
    options.edge_mm = edge;
    options.truth_settings = settings;
    try {
      const SyntheticCase s = makeSyntheticCase(options);
      const ProlapseResult& mesh = s.truth_metrics.mesh_prolapse;
      std::printf("| %llu | %s | %s |", static_cast<unsigned long long>(seed),
                  tool_support::joinedNames(mesh.segments).c_str(),
                  tool_support::joinedNames(s.truth_metrics.tracing_prolapse.segments).c_str());
      for (const char* name : {"A1", "A2", "A3", "P1", "P2", "P3"}) {
        const auto it = mesh.segment_max_height_mm.find(name);
        if (it == mesh.segment_max_height_mm.end()) {
          std::printf(" – |");
        } else {
          std::printf(" %.2f |", it->second);
        }
      }
      std::printf(" %.1f %% |", 100.0 * s.truth_metrics.orifice.coverage());
      std::printf(" %s (%d) | %d |\n", s.truth_result.converged ? "yes" : "no",
                  s.truth_result.steps, s.truth_retries);
      std::fflush(stdout);
    } catch (const std::exception& e) {
      std::cerr << "calibrate_cohort: " << preset.name << " seed " << seed << ": " << e.what()
                << "\n";
      return kExitFailed;
    }
  }
  return kExitOk;
}
