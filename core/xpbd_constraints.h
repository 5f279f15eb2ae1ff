// XPBD constraint kernels (Macklin, Mueller, Chentanez 2016, "XPBD: position-based simulation
// of compliant constrained dynamics", eqs. 17-18): for a constraint C with compliance alpha,
//   alpha~ = alpha / dt^2,
//   dlambda = (-C - alpha~ lambda) / (sum_i w_i |grad_i C|^2 + alpha~),
//   x_i += w_i grad_i C dlambda,
// w_i the inverse mass (0 for Dirichlet vertices). lambda is reset to 0 every time step.
//
// Positions are a flat array x[3 * i + d] (d = 0, 1, 2), inverse masses w[i]. Each batch
// function projects its constraints once, in array order (Gauss-Seidel), so the result is a
// deterministic function of the inputs. Constraint data is precomputed (rest values and
// compliances) and stored in plain arrays of structs.
//
// Unilateral constraints (cords, contacts) keep their accumulated lambda on the admissible
// sign (projected Gauss-Seidel): a cord only pulls, a contact only pushes.
#pragma once

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

// Paper eq. 1: C = |x_v - tip| - rest, active only when C >= 0 (the cord pulls, never
// pushes). The tip is Dirichlet: its position is read from a separate array, never moved.
struct CordConstraint {
  int tip = 0;     // index into the tip position array
  int vertex = 0;  // leaflet vertex
  double rest = 0.0;
  double compliance = 0.0;
};

// Vertex-triangle proximity contact, linearised once per time step: with the closest point
// q = ba x_a + bb x_b + bc x_c (barycentrics frozen) and the separating direction n (unit,
// frozen), C = n . (x_p - q) - thickness >= 0. Hard (compliance 0), pushes only.
struct ContactConstraint {
  int p = 0, a = 0, b = 0, c = 0;
  double ba = 0.0, bb = 0.0, bc = 0.0;
  double n[3] = {0.0, 0.0, 0.0};
  double thickness = 0.0;
};

// Batch projections. inv_dt2 = 1 / dt^2; lambda has one entry per constraint.
void projectDistances(const std::vector<DistanceConstraint>& constraints, double inv_dt2,
                      double* x, const double* w, double* lambda);
void projectBending(const std::vector<BendingConstraint>& constraints, double inv_dt2, double* x,
                    const double* w, double* lambda);
void projectAreas(const std::vector<AreaConstraint>& constraints, double inv_dt2, double* x,
                  const double* w, double* lambda);
// tips: flat tip positions tips[3 * t + d].
void projectCords(const std::vector<CordConstraint>& constraints, double inv_dt2,
                  const double* tips, double* x, const double* w, double* lambda);
void projectContacts(const std::vector<ContactConstraint>& constraints, double* x,
                     const double* w, double* lambda);

// Single-constraint evaluations (used to set up rest values and in tests).
// Signed dihedral angle at hinge (i, j) (see BendingConstraint); grad (optional) receives
// d theta / d x for i, j, k, l in that order. Returns 0 with zero gradient for degenerate
// faces.
double dihedralAngle(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj,
                     const Eigen::Vector3d& xk, const Eigen::Vector3d& xl,
                     Eigen::Vector3d* grad = nullptr);
// Triangle area; grad (optional) receives dA/dx for a, b, c.
double triangleArea(const Eigen::Vector3d& xa, const Eigen::Vector3d& xb,
                    const Eigen::Vector3d& xc, Eigen::Vector3d* grad = nullptr);
// Closest point of triangle (a, b, c) to p, as barycentrics (ba, bb, bc) (Ericson 2005,
// "Real-Time Collision Detection", sec. 5.1.5). Returns the region: 0 interior, 1 on an
// edge, 2 at a vertex.
int closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                           const Eigen::Vector3d& b, const Eigen::Vector3d& c, double& ba,
                           double& bb, double& bc);

}  // namespace chordfit
