// The simulator's settings: SimulationSettings with its defaults and the reasons for them,
// read from a case's "simulation" block (settingsFromJson) and range-checked
// (settingsProblems). The simulator itself is simulator.h.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/diagnostics.h"
#include "core/material.h"

namespace chordfit {

// Closing: pressure and flow push the leaflets toward the atrium while the annulus moves
// open -> closed. Opening: signs reversed, annulus closed -> open (the paper: "closed and
// opened by changing the signs of the fields").
enum class ClosurePhase { kClose, kOpen };

struct SimulationProgress {
  int step = 0;
  double time_ms = 0.0;
  double max_displacement_mm = 0.0;  // largest vertex displacement in the last step
  int contacts = 0;                  // contact constraints of the last step
};

struct SimulationSettings {
  LeafletMaterial material;
  // Transvalvular pressure (LV - LA) in systole; peak LV systolic pressure is ~120 mmHg
  // with LA pressure ~10 mmHg.
  double pressure_mmhg = 100.0;
  // Velocity field along n_AP during the ramp (the paper's "main flow direction"); the
  // leaflet velocity relaxes toward it with time constant drag_time_ms. After the ramp the
  // field is zero, so the drag only damps and the equilibrium does not depend on it.
  double flow_speed_mm_per_ms = 0.0;
  double drag_time_ms = 3.0;
  // Duration of the boundary interpolation (annulus, PM tips) and of the pressure ramp
  // (smoothstep 0 -> 1).
  // 10 ms (6 until 2026-11-25): a cold closure loaded faster than the leaflets can follow
  // overshoots, and a prolapsing flap then lands in one of two equilibria depending on tiny
  // differences of the input. With 6 ms a sweep of one cord of the bundled prolapse-P2 case
  // over +-5 % gave two values of the mean deviation (0.49 and 0.76-0.83 mm, alternating
  // within 0.1 % steps), and the true cords of four of the benchmark's six P2/flail cases made
  // no flap on the 2.5 mm case mesh; with 10 ms (also 12, 16) the sweep stays on one branch
  // and all six make it (8 ms: the sweep yes, two of the six no). docs/performance.md,
  // "Pressure ramp". A 1 ms ramp let the ~8,000-vertex valve fold sharply and diverge.
  double ramp_ms = 10.0;
  // Late drag: a closure still moving after `late_drag_after_steps` steps (a warm-started
  // closure, phase close with a start state: `late_drag_after_warm_steps`) gets the drag time
  // `late_drag_time_ms` from then on. A prolapsing flap can swing without end under the weak
  // default drag: the pressure on a sheet with a free edge is a follower load, not
  // conservative, and kinetic damping only removes the energy at its peaks (bileaflet truths
  // and fits on the 2.5 mm case meshes: the largest step 0.02-0.2 mm at the 5,000-step cap,
  // contacts toggling; measured 2026-11-25). The drag does not change the equilibrium, and
  // closures that settle before the switch are bit-identical: cold closures settle in
  // under 2,000 steps up to ~2,000 vertices (the bench valves of ~500 and ~2,000 vertices in
  // 736 and 1,907 with the 10 ms ramp), warm ones in 40-250. 0 disables it.
  int late_drag_after_steps = 2000;
  int late_drag_after_warm_steps = 500;
  double late_drag_time_ms = 0.5;
  // Time step; 0 selects dt from the mesh so that the median vertex has the stiffness ratio
  // k_i dt^2 / m_i = `stiffness_ratio`, k_i summing stretching, area and bending stiffness
  // (measured: the warm-started solve with 2 iterations is stable up to ratios of ~20 and
  // oscillates beyond, so the default keeps a margin); for a tissue softer than the default
  // 3 MPa, the step of the default tissue, and on meshes so fine that bending carries more
  // than 0.8 of the median vertex's stiffness, a smaller ratio (simulator.cpp, timeStepMs).
  double dt_ms = 0.0;
  double stiffness_ratio = 10.0;
  // Vertices stiffer than this (ratio k_i dt^2 / m_i) get a larger, fictitious mass (selective
  // mass scaling; the equilibrium does not depend on masses). <= 0 disables it.
  double max_stiffness_ratio = 15.0;
  // Kinetic damping (dynamic relaxation, Cundall 1976; Barnes 1999 "Form finding and
  // analysis of tension structures by dynamic relaxation"): after the ramp, whenever the total
  // kinetic energy drops, all velocities are set to zero.
  bool kinetic_damping = true;
  int iterations = 2;  // Gauss-Seidel sweeps per time step
  // Threads of one closure: each large colour class of the material constraints is split
  // between them (sweep_team.h); contacts, cords and the rest of the step stay on the calling
  // thread. Bit-identical results for any value. 1 where closures already run in parallel
  // (the fit's finite differences, sweeps over cords); a run option, not read from a case.
  int threads = 1;
  // Carry lambda across steps and apply the last step's constraint impulses in the
  // prediction (xpbd_constraints.h): the equilibrium is then the elastic one for any number
  // of iterations. false = textbook XPBD (lambda reset every step).
  bool warm_start_lambda = true;
  // Fraction of the contacts' impulses carried into the next prediction with the warm start
  // (the other constraints' impulses are carried whole). Carried whole, a contact's push moves
  // its vertex out of reach, the pair is not detected in the next step, the vertex falls back
  // and the pair forms again: a period-2 toggle that never settles (normal-1 fits, the
  // benchmark valve at some edges). Carried not at all, the warm-started closures lose their
  // consistency with the cold ones. 0.5 settles every toggling closure tried; on the
  // benchmark the fits' unsettled closures fell from 5.6 to 1.0 % (docs/performance.md,
  // "Contact impulses carried in part").
  double contact_impulse_carry = 0.5;
  // Largest allowed vertex displacement per step before the constraints (velocity clamp);
  // keeps contact detection from missing a crossing. <= 0: 0.25 * contact thickness.
  double max_step_mm = 0.0;
  double tolerance_mm = 1e-4;
  int window = 10;
  // Step cap. Closures that settle take under 2,000 steps up to ~2,000 vertices (the bench
  // valves 736 and 1,907 with the 10 ms ramp); those that do not settle (a cycle at a cord pulled
  // into a tent, a contact pair toggling before contact_impulse_carry; the largest step stays
  // at 0.003-0.1 mm, docs/performance.md) change by less than their own oscillation after a few
  // thousand steps, and a fit runs hundreds of closures, so the cap is 5,000 (it was 20,000: a
  // non-settling closure then cost 5 s instead of 1.2 s).
  int max_steps = 5000;
  // Step cap of a warm-started closure (phase close with a start state, as for the fit's finite
  // differences). Warm starts that settle take 40-250 steps (cohort, edge 2.5 mm); a
  // perturbation of a state that does not settle does not settle either, and running it to
  // max_steps only costs time (bileaflet seed 3: 196 of 196 perturbations ran to the cap).
  int max_warm_steps = 1500;
  // When a closure reaches its cap without settling, its result is the mean position over
  // its last `average_unsettled_steps` steps after the ramp (the centre of the residual
  // oscillation) rather than the last step's snapshot; `converged` stays false. 0: the last
  // state. The mean varies smoothly with the cords where the snapshot is a random phase of
  // the oscillation (docs/performance.md, "Closures that do not settle").
  int average_unsettled_steps = 1000;
  bool contact = true;
  // Also the midpoint of every mesh edge as a contact point against the triangles.
  // Vertex-triangle contact alone lets two coarse sheets cross edge through edge while every
  // vertex stays outside the other's thickness (docs/performance.md, "Self-intersections of
  // coarse closures"); the midpoints, held at 0.8 of the thickness as a backstop, removed them
  // on every benchmark closure that had them. true: always. false: only on a coarse mesh,
  // whose median rest edge is at least `edge_contact_edge_ratio` times the contact thickness
  // (crossings were seen at edges of 2-3 mm and never at 1.5 mm or finer with the 1 mm
  // default thickness). On the fine meshes the midpoints would cost 2.3x the time (the
  // 2,092-vertex valve 3.6 s instead of 1.6) for nothing; on the 2.5 mm case meshes they cost
  // 1.5x (measured 2026-11-25). edge_contact_edge_ratio 0: never automatically.
  bool edge_contact = false;
  double edge_contact_edge_ratio = 1.75;
  double contact_thickness_mm = 0.0;  // <= 0: material thickness
  double contact_margin_mm = 0.0;     // <= 0: 0.25 * contact thickness
  double contact_exclusion_mm = 0.0;  // <= 0: 2.5 * contact thickness (the list radius)
  // Area floor: no triangle's area may drop below this fraction of its rest area (a hard
  // unilateral constraint, xpbd_constraints.h); 0 disables it. The compliant area term
  // (area_bulk_fraction 0.1) lets free-edge triangles between two cords be squeezed to ~20 %
  // of their area, where they flutter and the closure never settles; the floor only acts on
  // such triangles, so closures that never squeeze a triangle below half its area are
  // bit-identical with or without it (docs/performance.md, "Area floor").
  double area_floor_fraction = 0.5;
  // Radius (mm) over which a cord's tension spreads into its leaflet around its insertion
  // point (cord_insertion.h: a smooth bump lumped to the vertices; a spread insertion is also
  // pulled at most max_step per sweep); 0: the whole tension at the point. Opt-in: on fine
  // meshes the tents of heavily loaded point insertions (15-20 N) cycle instead of settling
  // (the fine truths of normal-1 at the make-case default edge, 0.75 mm, ran to the step cap
  // with the largest step at 0.02-0.08 mm; so did the 0.6 mm references of mesh_convergence),
  // and with 2 mm they settle in 1,200-2,400 steps and the normal valves on coarser meshes
  // converge to them. Not the default, because the cohort is calibrated and benchmarked with
  // point insertions (docs/performance.md, "Cord insertion patch"); make-case's truths finer
  // than 0.75 mm use 2 mm (synthetic_case.h, truthSimulationSettings).
  double cord_insertion_radius_mm = 0.0;
  ClosurePhase phase = ClosurePhase::kClose;
  // Called every `progress_every` steps (0: never) and once at the end.
  int progress_every = 0;
  std::function<void(const SimulationProgress&)> progress;
};

// Overrides from a JSON object (a case's "simulation" block). Known keys, all optional:
//   pressure_mmhg, youngs_modulus_mpa, thickness_mm, poisson_ratio, density_g_per_cm3,
//   area_bulk_fraction, flexural_modulus_factor, flow_speed_mm_per_ms, drag_time_ms, ramp_ms,
//   late_drag_time_ms, dt_ms, stiffness_ratio, max_stiffness_ratio, iterations, warm_start_lambda,
//   contact_impulse_carry, max_step_mm, tolerance_mm, window, max_steps, max_warm_steps,
//   late_drag_after_steps, late_drag_after_warm_steps, average_unsettled_steps, contact,
//   edge_contact, edge_contact_edge_ratio, contact_thickness_mm, contact_margin_mm,
//   contact_exclusion_mm, area_floor_fraction, cord_insertion_radius_mm, kinetic_damping, phase
//   ("close" | "open").
// Unknown keys and wrong types are reported to `diagnostics` (file "case.json", where
// "simulation.<key>"); the remaining keys still apply.
// Values are range-checked (settingsProblems) after parsing; out-of-range values are reported
// as "simulation.<key>: <problem>" in `file`.
SimulationSettings settingsFromJson(const std::string& json, Diagnostics& diagnostics,
                                    const SimulationSettings& defaults = {},
                                    const std::string& file = "case.json");

// Range checks of the settings: every number finite, positive where the physics needs it,
// and below a sane upper bound (e.g. pressure_mmhg in (0, 500]: far above any physiological
// pressure, so a typo such as 1e300 is an input error, not a run). `key` is the JSON key of
// settingsFromJson; empty when all settings are acceptable. simulate() refuses settings with
// problems.
struct SettingsProblem {
  std::string key;
  std::string what;
};
std::vector<SettingsProblem> settingsProblems(const SimulationSettings& settings);

// The separation contact keeps between a vertex and a triangle of the mid-surface:
// contact_thickness_mm, or the material thickness when that is <= 0.
double contactThicknessMm(const SimulationSettings& settings);

// The largest step a vertex may take before the constraints (the velocity clamp): max_step_mm,
// or 0.25 x the contact thickness when that is 0 (automatic).
double velocityClampMm(const SimulationSettings& settings);

// Why a cold closure at time step dt_ms cannot settle because max_steps ends before the
// pressure ramp does ("" when it can), worded as a problem of max_steps.
std::string rampBeyondStepCap(const SimulationSettings& settings, double dt_ms);

}  // namespace chordfit
