// XPBD constraint kernels (Macklin, Mueller, Chentanez 2016, "XPBD: position-based simulation
// of compliant constrained dynamics", eqs. 17-18): for a constraint C with compliance alpha,
//   alpha~ = alpha / dt^2,
//   dlambda = (-C - alpha~ lambda) / (sum_i w_i |grad_i C|^2 + alpha~),
//   x_i += w_i grad_i C dlambda,
// w_i the inverse mass (0 for Dirichlet vertices). In the paper lambda is reset to 0 every
// time step; here it is carried over unless the settings turn warm_start_lambda off (below).
//
// Positions are a flat array x[3 * i + d] (d = 0, 1, 2), inverse masses w[i]. Each batch
// function projects its constraints once, in array order (Gauss-Seidel), so the result is a
// deterministic function of the inputs. Constraint data is precomputed (rest values and
// compliances) and stored in plain arrays of structs.
//
// Unilateral constraints (cords, contacts) keep their accumulated lambda on the admissible
// sign (projected Gauss-Seidel): a cord only pulls, a contact only pushes.
//
// Warm start: lambda is NOT reset between steps by the simulator. The constraint impulse of
// the last sweep, sum_j grad C_j lambda_j, is accumulated into `acc` (optional; a flat 3 #V
// array the caller zeroes) and applied in the next step's prediction, x~ += w * acc. At a
// steady state this makes every sweep a no-op exactly when C + alpha~ lambda = 0 and the
// forces balance, so the quasi-static equilibrium is the elastic one whatever the number of
// iterations (with lambda reset each step, a non-converged Gauss-Seidel solve leaves an
// iteration-dependent, too-soft material; see tests/test_xpbd_hencky.cpp). For a single
// linear constraint the warm-started step equals the reset XPBD step: only the initial guess
// of the implicit solve changes.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace chordfit {

// C = |x_i - x_j| - rest.
struct DistanceConstraint {
  int i = 0, j = 0;
  double rest = 0.0;
  double compliance = 0.0;
};

// C = theta - rest_angle, theta the signed dihedral angle at the hinge edge (i, j) between
// faces (i, j, k) and (j, i, l) (consistently wound; theta = 0 when flat, > 0 when folded
// toward the faces' normal side). Gradient: Bridson, Marino, Fedkiw 2003, "Simulation of
// clothing with folds and wrinkles", sec. 4.1 (bending modes u1..u4).
struct BendingConstraint {
  int i = 0, j = 0, k = 0, l = 0;
  double rest_angle = 0.0;
  double compliance = 0.0;
};

// C = A(x_a, x_b, x_c) - rest_area.
struct AreaConstraint {
  int a = 0, b = 0, c = 0;
  double rest_area = 0.0;
  double compliance = 0.0;
};

// Area floor, a hard unilateral constraint C = A(x_a, x_b, x_c) - min_area >= 0 (compliance
// 0), min_area a fraction of the rest area (SimulationSettings::area_floor_fraction). The
// compliant area term above stores an energy; this one only keeps a triangle from being
// squeezed flat, which the weak area term (K_a = 0.1 E h) allows (docs/performance.md, "Area
// floor"). Stored as an AreaConstraint with rest_area = min_area. Both area terms use the
// unsigned area, so a triangle turned inside out satisfies them; in the sheet bending resists
// that. Like the contacts, a floor starts each step from lambda = 0, but its impulse is
// carried into the next prediction in full (the contacts' in part): a review's one-triangle
// test held at rest on its floor showed the floor force alternating 3.96 <-> 15.53 N between
// steps. Carried in part like the contacts', the closures hardly change (the ~2,000-vertex
// valve 1,907 -> 1,885 steps; of the 52 closures of the benchmark cases with the heuristic's
// and the true cords, 12 by -7 to +45 steps, AvgD by at most 0.0003 mm, all settled), so it
// was left as calibrated.
//
// Paper eq. 1: C = |x_v - tip| - rest, active only when C >= 0 (the cord pulls, never
// pushes). The tip is Dirichlet: its position is read from a separate array, never moved.
// The insertion x_v is a leaflet vertex or a weighted mean of vertices, x_v = sum_m b_m x_m
// (a point of a triangle, core/cordset.h CordPoint, or a patch around it, cord_insertion.h);
// then grad_m C = b_m n, n = (x_v - tip) / |x_v - tip|, and the XPBD update (Macklin et al.
// 2016, eq. 18) is
//   dlambda = (-C - a lambda) / (sum_m b_m^2 w_m + a),  dx_m = b_m w_m n dlambda,
// with a = compliance / dt^2,
// which is the one-vertex update when the insertion is a vertex (one vertex, b_0 = 1). The
// cord's tension acts on vertex m as the force b_m T n.
struct CordConstraint {
  int tip = 0;                  // index into the tip position array
  std::vector<int> vertices;    // leaflet vertices of the insertion (>= 1)
  std::vector<double> weights;  // b_m >= 0, sum 1, one per vertex
  double rest = 0.0;
  double compliance = 0.0;
};

// Vertex-triangle proximity contact (Bridson, Fedkiw, Anderson 2002, "Robust treatment of
// collisions, contact and friction for cloth animation", proximity with thickness):
//   C = |x_p - q| - thickness >= 0, q the closest point of triangle (a, b, c) to x_p,
// evaluated afresh at every projection (barycentrics b_m by Ericson 2005). When q is interior
// to the triangle, |x_p - q| is replaced by side * n . (x_p - q) (n the unit normal, side
// = +-1 the side of the triangle x_p must stay on, fixed by the detector), so that a vertex
// that crossed the sheet over its interior is pushed back. Both forms agree, with their
// gradients, on the boundary of the interior region on x_p's own side only: a vertex that
// crossed the sheet and lies over an edge or corner region is pushed away from the edge on
// the side it is on, so such a crossing stays (it cannot be told there from a vertex that
// went round a free edge). The closure's self-intersection count reports it; no checked
// closure has shown one. Gradients: grad_p C = u, grad_m C = -b_m u with u the unit direction
// of C's increase (exact, checked against finite differences: over the interior the normal's
// derivative and the closest point's in-plane motion together give -b_m n).
// Hard (compliance 0), pushes only.
struct ContactConstraint {
  int p = 0, a = 0, b = 0, c = 0;
  // >= 0: the contact point is the midpoint of the edge (p, p2) instead of vertex p (edge
  // contact, SimulationSettings::edge_contact); its correction is shared by the two ends.
  int p2 = -1;
  double side = 1.0;  // +1: x_p stays on the side the winding normal points to; -1: other
  double thickness = 0.0;
};

// Batch projections of constraints[0 .. count). inv_dt2 = 1 / dt^2; lambda has one entry per
// constraint; acc optional (see above). The vector forms project the whole array.
void projectDistances(const DistanceConstraint* constraints, int count, double inv_dt2, double* x,
                      const double* w, double* lambda, double* acc = nullptr);
void projectBending(const BendingConstraint* constraints, int count, double inv_dt2, double* x,
                    const double* w, double* lambda, double* acc = nullptr);
void projectAreas(const AreaConstraint* constraints, int count, double inv_dt2, double* x,
                  const double* w, double* lambda, double* acc = nullptr);
// Area floors (rest_area = the floor, compliance ignored): like the contacts, lambda starts
// at 0 each step and stays >= 0; a floor that is not violated is skipped.
void projectAreaFloors(const AreaConstraint* constraints, int count, double* x, const double* w,
                       double* lambda, double* acc = nullptr);

inline void projectDistances(const std::vector<DistanceConstraint>& constraints, double inv_dt2,
                             double* x, const double* w, double* lambda, double* acc = nullptr) {
  projectDistances(constraints.data(), static_cast<int>(constraints.size()), inv_dt2, x, w, lambda,
                   acc);
}
inline void projectBending(const std::vector<BendingConstraint>& constraints, double inv_dt2,
                           double* x, const double* w, double* lambda, double* acc = nullptr) {
  projectBending(constraints.data(), static_cast<int>(constraints.size()), inv_dt2, x, w, lambda,
                 acc);
}
inline void projectAreas(const std::vector<AreaConstraint>& constraints, double inv_dt2, double* x,
                         const double* w, double* lambda, double* acc = nullptr) {
  projectAreas(constraints.data(), static_cast<int>(constraints.size()), inv_dt2, x, w, lambda,
               acc);
}
inline void projectAreaFloors(const std::vector<AreaConstraint>& constraints, double* x,
                              const double* w, double* lambda, double* acc = nullptr) {
  projectAreaFloors(constraints.data(), static_cast<int>(constraints.size()), x, w, lambda, acc);
}

// tips: flat tip positions tips[3 * t + d].
// max_pull > 0: one projection moves a cord's insertion by at most max_pull toward its tip
// (dlambda clamped to -max_pull / sum_m b_m^2 w_m): no insertion is dragged across the mesh in
// one sweep, and as dlambda vanishes at equilibrium the equilibrium is the same.
void projectCords(const std::vector<CordConstraint>& constraints, double inv_dt2,
                  const double* tips, double* x, const double* w, double* lambda,
                  double* acc = nullptr, double max_pull = 0.0);
void projectContacts(const std::vector<ContactConstraint>& constraints, double* x, const double* w,
                     double* lambda, double* acc = nullptr);

// The colour classes of an array ordered by orderByColour: class k is [starts[k],
// starts[k + 1]). Constraints of one class share no vertex, except in the last class when
// `last_shared` (every one of the 64 colours was taken at some vertex).
struct ColourClasses {
  std::vector<int> starts{0};
  bool last_shared = false;
  int count() const { return static_cast<int>(starts.size()) - 1; }
};

// Reorders constraints by a greedy vertex colouring (stable within a colour): constraints of
// one colour share no vertex, so consecutive projections do not wait on each other's writes
// (a Gauss-Seidel sweep in natural order is latency-bound: each projection reads the vertex
// the previous one just wrote), and a colour can be split between threads without changing a
// bit (sweep_team.h). Any fixed order is a valid Gauss-Seidel order; this one is a
// deterministic function of the input order. vertices_of(c) returns a std::array<int, N>.
template <class Constraint, class VerticesOf>
ColourClasses orderByColour(std::vector<Constraint>& constraints, VerticesOf vertices_of) {
  constexpr int kShared = 64;  // all 64 colours taken: a last, shared class
  int max_vertex = -1;
  for (const Constraint& c : constraints)
    for (int v : vertices_of(c)) max_vertex = std::max(max_vertex, v);
  std::vector<std::uint64_t> used(static_cast<size_t>(max_vertex + 1), 0);
  std::vector<std::pair<int, int>> key(constraints.size());  // (colour, original index)
  for (size_t k = 0; k < constraints.size(); ++k) {
    std::uint64_t mask = 0;
    for (int v : vertices_of(constraints[k])) mask |= used[v];
    int colour = kShared;
    for (int b = 0; b < kShared; ++b)
      if (!(mask & (std::uint64_t{1} << b))) {
        colour = b;
        break;
      }
    if (colour < kShared)
      for (int v : vertices_of(constraints[k])) used[v] |= std::uint64_t{1} << colour;
    key[k] = {colour, static_cast<int>(k)};
  }
  std::sort(key.begin(), key.end());
  std::vector<Constraint> sorted;
  sorted.reserve(constraints.size());
  ColourClasses classes;
  for (size_t k = 0; k < key.size(); ++k) {
    sorted.push_back(constraints[key[k].second]);
    if (k + 1 == key.size() || key[k + 1].first != key[k].first) {
      classes.starts.push_back(static_cast<int>(k + 1));
      classes.last_shared = key[k].first == kShared;
    }
  }
  constraints.swap(sorted);
  return classes;
}

// Single-constraint evaluations (used to set up rest values and in tests).
// Signed dihedral angle at hinge (i, j) (see BendingConstraint); grad (optional) receives
// d theta / d x for i, j, k, l in that order. Returns 0 with zero gradient for degenerate
// faces.
double dihedralAngle(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj,
                     const Eigen::Vector3d& xk, const Eigen::Vector3d& xl,
                     Eigen::Vector3d* grad = nullptr);
// Triangle area; grad (optional) receives dA/dx for a, b, c.
double triangleArea(const Eigen::Vector3d& xa, const Eigen::Vector3d& xb, const Eigen::Vector3d& xc,
                    Eigen::Vector3d* grad = nullptr);
// Closest point of triangle (a, b, c) to p, as barycentrics (ba, bb, bc) (Ericson 2005,
// "Real-Time Collision Detection", sec. 5.1.5). Returns the region: 0 interior, 1 on an
// edge, 2 at a vertex.
int closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                           const Eigen::Vector3d& b, const Eigen::Vector3d& c, double& ba,
                           double& bb, double& bc);

}  // namespace chordfit
