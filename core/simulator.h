// XPBD closure simulator (DESIGN §4; paper "Mitral valve model and simulation" and
// "Modeling of tendinous cords"; Macklin et al. 2016 for XPBD).
//
// Model: leaflet membrane (edge distance, dihedral bending and triangle area constraints with
// compliances from material.h, optionally scaled per region: tissue_stiffness), cords (paper
// eq. 1: a distance constraint PM tip -> leaflet vertex or a point between vertices, active
// only when stretched), Dirichlet annulus ring and PM tips (interpolated from their start to
// their end positions during the ramp), systolic pressure along the area-weighted vertex
// normals (ventricle -> atrium), a velocity field along the annulus-plane normal n_AP with
// viscous drag toward it, and vertex-triangle contact (contact.h).
// Units: mm, g, ms, N, MPa (material.h).
//
// Time step (simulator.cpp, Stepper): predict (v += dt f/m, drag, x~ = x + dt v + w impulse),
// solve (Gauss-Seidel: edges, areas, bending, contacts, cords), update (v = (x - x_prev)/dt).
// Only the quasi-static equilibrium is used, which shapes three choices:
//   - lambda is warm-started across steps for the material and the cords (xpbd_constraints.h),
//     so the equilibrium is the elastic one with 2 iterations (textbook XPBD would be
//     iteration-dependent and too soft: tests/test_xpbd_hencky.cpp). Contacts are detected
//     anew every step with lambda = 0 (carrying it made the closure oscillate); the price is
//     an O(dt^2) softness: at equilibrium a contact vertex sits dt^2 w f_contact (~0.01 mm)
//     inside the thickness as the material sees it.
//   - dt is chosen from the stiffness (stretching + area + bending) to mass ratio, and
//     vertices stiffer than max_stiffness_ratio get a fictitious larger mass (selective mass
//     scaling): the warm-started solve is stable up to ratios of ~20.
//   - a displacement clamp of max_step per step keeps contact detection from missing a
//     crossing.
//
// Path to equilibrium: after the ramp, kinetic damping (all velocities zeroed whenever the
// total kinetic energy drops) plus a weak drag; only the path changes, not the equilibrium
// (docs/performance.md: 881 -> 516 steps for the default valve, warm starts 207 -> 60).
//
// Equilibrium criterion (quasi-static): after the ramp, the largest displacement of any
// vertex within one time step stays below `tolerance_mm` for `window` consecutive steps.
// NaN or an exploding position (or a jump of more than half the model radius in one step)
// ends the run with `error` set and no positions.
//
// Determinism: Gauss-Seidel over constraint arrays in a fixed order (sorted by a greedy
// colouring, for instruction-level parallelism and for `threads`: a colour class split between
// threads gives the same bits as the class in order); contact detection is order-deterministic;
// no static mutable state. Same input => bit-identical output, whatever `threads` and the thread
// count of the caller (the inverse layer parallelises over forward runs instead).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"
#include "core/cordset.h"
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
  // 300-1,700 steps up to ~2,000 vertices, warm ones in 40-250. 0 disables it.
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
  // Step cap. Closures that settle take 300-1,700 steps up to ~2,000 vertices (measured on
  // the cohort and bench-sim valves); those that do not settle (a cycle at a cord pulled
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

// Whether a closure of the mesh (V_rest, F) uses edge contact: settings.edge_contact, or the
// median rest edge length >= settings.edge_contact_edge_ratio * contact thickness (> 0).
bool usesEdgeContact(const SimulationSettings& settings, const Eigen::MatrixXd& V_rest,
                     const Eigen::MatrixXi& F, double contact_thickness_mm);

// A simulation problem in plain arrays. simulateClosure builds one from a case; tests and
// benchmarks may build their own (e.g. a clamped disc).
struct SimulationModel {
  Eigen::MatrixXd V_rest;  // #V by 3 rest state (open): rest lengths, angles, areas, masses
  // #F by 3, consistently wound; the pressure force acts along the winding normal
  // (right-hand rule), i.e. the winding normal points to the side the pressure pushes to.
  Eigen::MatrixXi F;
  Eigen::VectorXi fixed;        // Dirichlet vertex indices
  Eigen::MatrixXd fixed_start;  // #fixed by 3 positions at t = 0
  Eigen::MatrixXd fixed_end;    // #fixed by 3 positions from the end of the ramp on
  Eigen::MatrixXd tip_start;    // #tips by 3 PM tip positions at t = 0
  Eigen::MatrixXd tip_end;      // #tips by 3 PM tip positions from the end of the ramp on
  struct Cord {
    int tip = 0, vertex = 0;
    double rest_length = 0.0;        // mm
    double compliance = 0.0;         // mm/N
    std::optional<CordPoint> point;  // insertion between vertices (then `vertex` is unused)
  };
  std::vector<Cord> cords;
  Eigen::Vector3d flow_direction = Eigen::Vector3d::UnitZ();  // unit; velocity field direction
  // Regional tissue (optional; empty = uniform): one factor > 0 per vertex on the leaflet
  // material's stiffness, e.g. myxomatous tissue softer than the rest. A constraint's
  // stiffness (stretching, area, bending) is the uniform one times the mean factor of its
  // vertices; masses do not change (ValveCase::tissue_stiffness).
  Eigen::VectorXd tissue_stiffness;
};

struct SimulationResult {
  Eigen::MatrixXd V;           // #V by 3 final positions (empty when error is set)
  Eigen::MatrixXd tips;        // #tips by 3 final PM tip positions
  Eigen::VectorXd cord_force;  // #cords cord tension at the end, N (0 when slack)
  bool converged = false;      // equilibrium criterion met before max_steps
  int steps = 0;
  double seconds = 0.0;              // wall time of the time loop (model setup included)
  double cpu_seconds = 0.0;          // CPU time of the calling thread, same span
  double dt_ms = 0.0;                // time step used
  double max_displacement_mm = 0.0;  // of the last step
  int mass_scaled_vertices = 0;      // vertices that got a fictitious mass
  int contact_rebuilds = 0;          // contact candidate-list builds (contact.h)
  int contact_candidates = 0;        // candidate pairs in the last list
  int contacts = 0;                  // active contact constraints (lambda > 0) at the end
  long long projections = 0;         // constraint projections performed (for ns/projection)
  int kinetic_stops = 0;             // velocity resets by kinetic damping
  bool late_drag = false;            // the late drag (SimulationSettings) was switched on
  bool edge_contact = false;         // edge midpoints were contact points (set or coarse mesh)
  // threads > 1 only: the helper threads were stopped because the calling thread kept waiting
  // for them (a machine with more runnable threads than cores; sweep_team.h); the rest of the
  // closure ran on one thread, with the same result.
  bool threads_gave_up = false;
  int averaged_steps = 0;  // > 0: not settled, V is the mean over this many final steps
  std::string error;       // non-empty: invalid input or divergence (NaN/explosion)
  bool diverged = false;   // the error is a divergence (not invalid input)
  bool ok() const { return error.empty(); }
};

// The model of a case's closure (phase kClose) or opening (kOpen):
//   - F consistently oriented; per connected component the winding normal is chosen to point
//     to the atrial side (toward n_AP and toward the valve axis; DESIGN §4);
//   - fixed = mesh.annulus, open positions mesh.V, closed positions case.annulus_closed
//     (static at the open positions if annulus_closed is empty);
//   - tips from `cords.tips` (closed_position when given, else static);
//   - flow_direction = n_AP of openAnnulusFrame (toward the atrium); reversed for kOpen.
// Returns false and sets `error` on inconsistent input (indices out of range, sizes).
bool closureModel(const ValveCase& valve_case, const CordSet& cords, ClosurePhase phase,
                  SimulationModel& model, std::string& error);

// Runs the model to quasi-static equilibrium.
// start  optional #V by 3 start positions (warm start, e.g. a previous closed state). With a
//        start, the Dirichlet vertices and tips are placed at their end positions and there
//        is no ramp (the flow field is off); without one the run starts from V_rest with the
//        boundary at its start positions.
SimulationResult simulate(const SimulationModel& model, const SimulationSettings& settings,
                          const Eigen::MatrixXd* start = nullptr);

// The time step a closure of `model` takes, ms: settings.dt_ms, or the automatic step of its
// mesh and material when that is 0.
double closureTimeStepMs(const SimulationModel& model, const SimulationSettings& settings);

// Why a cold closure at time step dt_ms cannot settle because max_steps ends before the
// pressure ramp does ("" when it can), worded as a problem of max_steps.
std::string rampBeyondStepCap(const SimulationSettings& settings, double dt_ms);

// closureModel + simulate. For phase kOpen a warm start (the closed state) is required.
SimulationResult simulateClosure(const ValveCase& valve_case, const CordSet& cords,
                                 const SimulationSettings& settings,
                                 const Eigen::MatrixXd* warm_start = nullptr);

}  // namespace chordfit
