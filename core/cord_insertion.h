// Where a cord's tension acts on the leaflet.
//
// The paper links a PM tip to one leaflet vertex, and the synthetic cohort links it to a point
// of a triangle (CordPoint); either way the whole tension acts at one point of the mesh, up to
// ~20 N on the cohort's fine truths, and the tent it pulls into the leaflet is as sharp as the
// mesh allows. On fine meshes the two-sweep warm-started solver cycles around such tents
// instead of settling, and the normal valves converge poorly with the mesh (docs/performance.md,
// "Cord insertion patch"; the leaflet's bending stiffness keeps a point load finite, so it is
// not a continuum singularity). Chordae do not insert at a point either: they branch and fan
// out into the leaflet over millimetres.
//
// The patch spreads the tension over the rest surface with a smooth kernel of radius r about
// the insertion point p0, k(d) = (1 - d^2/r^2)^2 for d < r (a compact bump), lumped to the
// vertices with the linear hat functions phi_i of the mesh:
//   b_i = integral k(|y - p0|) phi_i(y) dA / integral k(|y - p0|) dA,
// the weights of the insertion x_v = sum_i b_i x_i in the cord constraint (xpbd_constraints.h):
// vertex i then carries the force b_i T n, the discretisation of a load density T k / int k
// that is the same on every mesh. The integrals are sums over sub-triangles of the triangles
// within reach (each split so that its sub-triangles are smaller than r/4). As r -> 0 the
// weights become p0's barycentric coordinates, the point insertion.
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/cordset.h"
#include "core/valve_mesh.h"

namespace chordfit {

struct CordInsertionWeights {
  std::vector<int> vertices;    // a spread insertion: the vertices it reaches, ascending
  std::vector<double> weights;  // b_i >= 0, summing to 1
};

// The insertion at the point sum_m point_weights[m] V(point_vertices[m]) spread over radius
// `radius_mm` of the surface (V, F) (V #V by 3 rest positions, F #F by 3). radius_mm <= 0, or a
// patch that no triangle reaches, gives the point itself (its vertices and weights as given).
CordInsertionWeights cordInsertionWeights(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                          const std::vector<int>& point_vertices,
                                          const std::vector<double>& point_weights,
                                          double radius_mm);

// The same for a cord that inserts at `point` (a point of a triangle) or, without one, at
// `vertex`.
CordInsertionWeights cordInsertionWeights(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                          int vertex, const std::optional<CordPoint>& point,
                                          double radius_mm);

// Every cord's insertion as the simulator builds it: cordInsertionWeights of its point (or
// vertex) on the rest mesh (mesh.V, mesh.F). The rest lengths and tips of the set do not
// matter, so a fit computes them once. #cords entries.
std::vector<CordInsertionWeights> cordInsertions(const ValveMesh& mesh, const CordSet& set,
                                                 double radius_mm);

// sum_i b_i V(i): where the cord inserts in the state V.
Eigen::Vector3d insertionPosition(const CordInsertionWeights& insertion, const Eigen::MatrixXd& V);

// Each cord's span in a closed state: |insertion - tip|, the insertion as the simulator spreads
// it (`insertions`, cordInsertions of the set's mesh), the tip at its closed position (or its
// open one when it has none, as the simulator keeps it). A cord is slack there when its span is
// below its rest length (paper eq. 1: no force), and then any rest length down to its span
// closes the valve the same way: the closed state bounds a slack cord's length from below
// only. #cords values, mm.
Eigen::VectorXd closedSpans(const CordSet& set, const std::vector<CordInsertionWeights>& insertions,
                            const Eigen::MatrixXd& V_closed);

}  // namespace chordfit
