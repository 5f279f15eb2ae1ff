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
// solve (Gauss-Seidel: edges, areas, bending, area floors, contacts, cords), update
// (v = (x - x_prev)/dt).
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

#include "core/cordset.h"
#include "core/simulation_settings.h"

namespace chordfit {

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

}  // namespace chordfit
