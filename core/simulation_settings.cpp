#include "core/simulation_settings.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/json_fields.h"
#include "core/quoted_text.h"

namespace chordfit {

std::string rampBeyondStepCap(const SimulationSettings& settings, double dt_ms) {
  if (!(dt_ms > 0.0) || settings.ramp_ms / dt_ms <= settings.max_steps) return "";
  char what[240];
  std::snprintf(what, sizeof what,
                "%d ends before the %g ms pressure ramp does (%.0f steps at dt = %.4g ms%s); "
                "raise max_steps or shorten ramp_ms",
                settings.max_steps, settings.ramp_ms, std::ceil(settings.ramp_ms / dt_ms), dt_ms,
                settings.dt_ms == 0.0 ? ", the automatic step for this mesh" : "");
  return what;
}

std::vector<SettingsProblem> settingsProblems(const SimulationSettings& s) {
  // Accepted interval per setting: (lo, hi] when lo_open, else [lo, hi]. The upper bounds are
  // generous (several times any physiological or numerically useful value); they exist so
  // that a typo is an input error rather than a run that "converges" to nonsense.
  struct Range {
    const char* key;
    double value;
    double lo;
    bool lo_open;
    double hi;
  };
  const LeafletMaterial& m = s.material;
  const Range ranges[] = {
      {"pressure_mmhg", s.pressure_mmhg, 0.0, true, 500.0},
      // Lower bounds far below any tissue but above the values that made the automatic step
      // count overflow (1e-300 g/cm³ printed a 150-digit step count blaming max_steps).
      {"youngs_modulus_mpa", m.youngs_modulus_mpa, 1e-3, false, 1000.0},
      {"thickness_mm", m.thickness_mm, 0.0, true, 10.0},
      {"poisson_ratio", m.poisson_ratio, -1.0, true, 0.499},
      {"density_g_per_cm3", m.density_g_per_cm3, 1e-3, false, 100.0},
      {"area_bulk_fraction", m.area_bulk_fraction, 0.0, false, 100.0},
      {"flexural_modulus_factor", m.flexural_modulus_factor, 0.0, true, 100.0},
      {"flow_speed_mm_per_ms", s.flow_speed_mm_per_ms, 0.0, false, 100.0},
      {"drag_time_ms", s.drag_time_ms, 0.0, true, 1e4},
      {"ramp_ms", s.ramp_ms, 0.0, false, 1e4},
      {"late_drag_time_ms", s.late_drag_time_ms, 0.0, true, 1e4},
      {"edge_contact_edge_ratio", s.edge_contact_edge_ratio, 0.0, false, 1e3},
      {"contact_impulse_carry", s.contact_impulse_carry, 0.0, false, 1.0},
      {"dt_ms", s.dt_ms, 0.0, false, 10.0},  // 0 = automatic
      {"stiffness_ratio", s.stiffness_ratio, 0.0, true, 1000.0},
      // Any finite value <= 0 turns it off (-1e308 was refused as "at most 1e4").
      {"max_stiffness_ratio", s.max_stiffness_ratio, std::numeric_limits<double>::lowest(), false,
       1e4},
      {"max_step_mm", s.max_step_mm, 0.0, false, 100.0},  // 0: automatic
      {"tolerance_mm", s.tolerance_mm, 0.0, true, 10.0},
      {"contact_thickness_mm", s.contact_thickness_mm, 0.0, false, 10.0},  // 0: automatic
      {"contact_margin_mm", s.contact_margin_mm, 0.0, false, 10.0},
      {"contact_exclusion_mm", s.contact_exclusion_mm, 0.0, false, 100.0},
      {"area_floor_fraction", s.area_floor_fraction, 0.0, false, 0.99},
      {"cord_insertion_radius_mm", s.cord_insertion_radius_mm, 0.0, false, 20.0},
      {"iterations", static_cast<double>(s.iterations), 1.0, false, 1000.0},
      {"threads", static_cast<double>(s.threads), 1.0, false, 64.0},
      {"window", static_cast<double>(s.window), 1.0, false, 1e6},
      {"max_steps", static_cast<double>(s.max_steps), 1.0, false, 1e8},
      {"max_warm_steps", static_cast<double>(s.max_warm_steps), 1.0, false, 1e8},
      {"average_unsettled_steps", static_cast<double>(s.average_unsettled_steps), 0.0, false, 1e8},
      {"late_drag_after_steps", static_cast<double>(s.late_drag_after_steps), 0.0, false, 1e8},
      {"late_drag_after_warm_steps", static_cast<double>(s.late_drag_after_warm_steps), 0.0, false,
       1e8},
  };
  std::vector<SettingsProblem> problems;
  for (const Range& r : ranges) {
    const bool above_lo = r.lo_open ? r.value > r.lo : r.value >= r.lo;
    if (!std::isfinite(r.value)) {
      problems.push_back({r.key, "must be a finite number"});
    } else if (!above_lo || r.value > r.hi) {
      char what[160];
      if (r.lo <= -1e300)
        std::snprintf(what, sizeof what, "%g is out of range (at most %g)", r.value, r.hi);
      else
        std::snprintf(what, sizeof what, "%g is out of range %s%g, %g]", r.value,
                      r.lo_open ? "(" : "[", r.lo, r.hi);
      problems.push_back({r.key, what});
    }
  }
  // A given time step must be one a closure can use: kMinDtMs is about a thousandth of the
  // automatic step of the finest meshes run (0.3 mm edges), below which every step moves the
  // valve less than the tolerance; and the pressure ramp alone must fit under the step cap, or
  // no closure can settle (dt_ms = 1e-300 used to pass and fail only in the run, exit 3).
  constexpr double kMinDtMs = 1e-6;
  if (s.dt_ms > 0.0 && s.dt_ms < kMinDtMs) {
    char what[160];
    std::snprintf(what, sizeof what, "%g is below %g ms (0 = automatic)", s.dt_ms, kMinDtMs);
    problems.push_back({"dt_ms", what});
  } else if (s.dt_ms > 0.0 && s.max_steps >= 1) {
    if (const std::string problem = rampBeyondStepCap(s, s.dt_ms); !problem.empty())
      problems.push_back({"max_steps", problem});
  }
  // The closure settles when no vertex moves more than tolerance_mm per step; a velocity clamp
  // at or near it would meet that criterion with the valve still moving at the clamp
  // (max_step_mm 5e-5 reported a closure "converged" after 159 steps, 39 % of the orifice
  // open; tolerance_mm 0.3 against the automatic 0.25 mm clamp, right after the ramp). 10x
  // keeps a settled valve apart from a clamped one.
  constexpr double kMinStepToTolerance = 10.0;
  const bool automatic_clamp = !(s.max_step_mm > 0.0);
  const double clamp = velocityClampMm(s);
  if (std::isfinite(clamp) && clamp > 0.0 && std::isfinite(s.tolerance_mm) &&
      s.tolerance_mm > 0.0 && clamp < kMinStepToTolerance * s.tolerance_mm) {
    char what[300];
    if (automatic_clamp)
      std::snprintf(what, sizeof what,
                    "%g mm is more than a tenth of the largest step a vertex may take (%g mm, "
                    "0.25 x the contact thickness): a closure would pass the settling test while "
                    "still moving",
                    s.tolerance_mm, clamp);
    else
      std::snprintf(what, sizeof what,
                    "%g mm is below %g x tolerance_mm (%g mm): a closure clamped to it would pass "
                    "the settling test while still moving (0 = automatic, 0.25 x the contact "
                    "thickness)",
                    s.max_step_mm, kMinStepToTolerance, s.tolerance_mm);
    problems.push_back({automatic_clamp ? "tolerance_mm" : "max_step_mm", what});
  }
  return problems;
}

double contactThicknessMm(const SimulationSettings& settings) {
  return settings.contact_thickness_mm > 0.0 ? settings.contact_thickness_mm
                                             : settings.material.thickness_mm;
}

double velocityClampMm(const SimulationSettings& settings) {
  return settings.max_step_mm > 0.0 ? settings.max_step_mm : 0.25 * contactThicknessMm(settings);
}

SimulationSettings settingsFromJson(const std::string& json, Diagnostics& diagnostics,
                                    const SimulationSettings& defaults, const std::string& file) {
  SimulationSettings s = defaults;
  const auto parsed = parseJson(json, file, diagnostics);
  if (!parsed) return s;
  JsonFields fields(file, diagnostics);
  if (!parsed->is_object()) {
    fields.typeError("simulation", "object", *parsed);
    return s;
  }
  struct NumberKey {
    const char* key;
    double* target;
  };
  const NumberKey numbers[] = {
      {"pressure_mmhg", &s.pressure_mmhg},
      {"youngs_modulus_mpa", &s.material.youngs_modulus_mpa},
      {"thickness_mm", &s.material.thickness_mm},
      {"poisson_ratio", &s.material.poisson_ratio},
      {"density_g_per_cm3", &s.material.density_g_per_cm3},
      {"area_bulk_fraction", &s.material.area_bulk_fraction},
      {"flexural_modulus_factor", &s.material.flexural_modulus_factor},
      {"flow_speed_mm_per_ms", &s.flow_speed_mm_per_ms},
      {"drag_time_ms", &s.drag_time_ms},
      {"ramp_ms", &s.ramp_ms},
      {"late_drag_time_ms", &s.late_drag_time_ms},
      {"contact_impulse_carry", &s.contact_impulse_carry},
      {"edge_contact_edge_ratio", &s.edge_contact_edge_ratio},
      {"dt_ms", &s.dt_ms},
      {"stiffness_ratio", &s.stiffness_ratio},
      {"max_stiffness_ratio", &s.max_stiffness_ratio},
      {"max_step_mm", &s.max_step_mm},
      {"tolerance_mm", &s.tolerance_mm},
      {"contact_thickness_mm", &s.contact_thickness_mm},
      {"contact_margin_mm", &s.contact_margin_mm},
      {"contact_exclusion_mm", &s.contact_exclusion_mm},
      {"area_floor_fraction", &s.area_floor_fraction},
      {"cord_insertion_radius_mm", &s.cord_insertion_radius_mm},
  };
  struct IntKey {
    const char* key;
    int* target;
  };
  const IntKey integers[] = {{"iterations", &s.iterations},
                             {"window", &s.window},
                             {"max_steps", &s.max_steps},
                             {"max_warm_steps", &s.max_warm_steps},
                             {"average_unsettled_steps", &s.average_unsettled_steps},
                             {"late_drag_after_steps", &s.late_drag_after_steps},
                             {"late_drag_after_warm_steps", &s.late_drag_after_warm_steps}};
  for (const auto& [key, value] : parsed->items()) {
    const std::string where = "simulation." + key;
    bool known = false;
    for (const auto& nk : numbers)
      if (key == nk.key) {
        known = true;
        double out;
        if (fields.number(value, where, out)) *nk.target = out;
      }
    for (const auto& ik : integers)
      if (key == ik.key) {
        known = true;
        int out;
        if (fields.integer(value, where, out)) *ik.target = out;
      }
    if (key == "contact" || key == "edge_contact" || key == "warm_start_lambda" ||
        key == "kinetic_damping") {
      known = true;
      bool out;
      if (fields.boolean(value, where, out))
        (key == "contact"           ? s.contact
         : key == "edge_contact"    ? s.edge_contact
         : key == "kinetic_damping" ? s.kinetic_damping
                                    : s.warm_start_lambda) = out;
    } else if (key == "phase") {
      known = true;
      std::string out;
      if (fields.text(value, where, out)) {
        if (out == "close")
          s.phase = ClosurePhase::kClose;
        else if (out == "open")
          s.phase = ClosurePhase::kOpen;
        else
          fields.error(where, "expected \"close\" or \"open\", got " + quotedText(out));
      }
    }
    if (!known) {
      std::vector<std::string> names = {"contact", "edge_contact", "warm_start_lambda",
                                        "kinetic_damping"};
      for (const auto& nk : numbers) names.emplace_back(nk.key);
      for (const auto& ik : integers) names.emplace_back(ik.key);
      fields.error(where, "unknown simulation setting" + typoSuggestion(key, names));
    }
  }
  for (const SettingsProblem& problem : settingsProblems(s))
    fields.error("simulation." + problem.key, problem.what);
  return s;
}

}  // namespace chordfit
