// Vertex-triangle proximity contact with thickness, for leaflet coaptation and self-contact.
//
// Once per time step the detector finds every (vertex p, triangle T) pair with
// dist(p, T) < thickness + margin at the predicted positions and makes it a ContactConstraint
// C = n . (x_p - q) - thickness >= 0 (xpbd_constraints.h), whose closest point q and normal n
// are recomputed at every projection (contactStateAt):
//   - q = closest point of T to p (Ericson 2005),
//   - n = T's unit normal, signed to the side where p was at the START of the step, when the
//     closest point is interior to T. A vertex that crossed T during the prediction is pushed
//     back to its own side. (The start-of-step state is free of crossings as long as no
//     projection after the contacts, a cord's, pulls a vertex through a sheet within one step;
//     the closures' self-intersection count, metrics.json, would show one that did);
//   - n = (p - q) / |p - q| when q lies on an edge or a vertex of T (no side to lose there;
//     this makes the direction continuous across the region boundary).
// Pairs that are close in the rest state are excluded: T containing p, and T with a vertex
// within `exclusion_radius` of p in the rest (open) state, so that bending of the sheet itself
// does not register as contact.
//
// Broad phase: a Verlet list of candidate pairs within thickness + margin + skin, rebuilt
// only when some vertex has moved more than skin / 2 since the last build (then no pair
// outside the list can have come within thickness + margin: a vertex-triangle distance
// changes by at most twice the largest vertex displacement). Each candidate keeps its
// distance at the build; the per-step filter skips a pair whose lower bound
//   dist_now >= dist_built - moved(p) - max(moved(a), moved(b), moved(c))
// (moved = a vertex's displacement since the build; every point of the triangle moves at most
// as far as its farthest vertex) is already beyond thickness + margin, so it computes closest
// points only for pairs that can be within reach: the same constraints, far fewer closest
// points once the motion has slowed down. The list is built on a dense
// uniform grid over the bounding box of the vertices (Ten Minute Physics "self-collision"
// lesson, with a dense table instead of a hash since the valve is compact): vertices are
// counting-sorted by cell, x fastest, so the cells of one grid row of a triangle's inflated
// bounding box are one contiguous run of vertices. Candidates are ordered by triangle, then
// vertex index, so the output is deterministic.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/sweep_team.h"
#include "core/xpbd_constraints.h"

namespace chordfit {

struct ContactOptions {
  double thickness_mm = 1.0;         // target separation of a vertex from a triangle
  double margin_mm = 0.5;            // pairs within thickness + margin become constraints
  double exclusion_radius_mm = 2.5;  // rest-state neighbourhood ignored (see above)
  double skin_mm = 1.0;              // Verlet-list skin (see above)
};

// The constraint of vertex p against triangle (a, b, c) for one step: its side is that of the
// start-of-step plane of the triangle (the predicted plane if p lies in it), see above.
// x_start, x_pred flat positions (3 #V).
ContactConstraint contactConstraint(int p, int a, int b, int c, const double* x_start,
                                    const double* x_pred, double thickness);

class ContactDetector {
 public:
  // V_rest  #V by 3 rest (open) state, used for the exclusion test and the cell size
  // F       #F by 3 triangles (winding defines the normal's sign, not the contact side)
  ContactDetector(const Eigen::MatrixXd& V_rest, const Eigen::MatrixXi& F,
                  const ContactOptions& options);

  // x_start, x_pred  flat positions (3 #V) at the start of the step and predicted
  // w                inverse masses; pairs whose vertices all have w = 0 are skipped
  // out              replaced with the step's contact constraints
  // team             optional: the candidate build's triangles and the per-step filter's
  //                  candidates are cut into one contiguous part per thread, and the parts'
  //                  results concatenated in order, so `out` is the same with or without it
  void detect(const double* x_start, const double* x_pred, const double* w,
              std::vector<ContactConstraint>& out, SweepTeam* team = nullptr);

  const ContactOptions& options() const { return options_; }
  int rebuilds() const { return rebuilds_; }  // candidate-list builds so far
  int candidates() const { return static_cast<int>(candidates_.size()); }

 private:
  // One thread's share of the work, and its scratch.
  struct Part {
    std::vector<std::pair<int, int>> candidates;  // build: (triangle, vertex) pairs found
    std::vector<double> distance;                 // build: their distances
    std::vector<int> near;  // one grid row's vertices in the triangle's sphere, not excluded
    std::vector<std::pair<int, double>> hits;  // one triangle's (vertex, distance)
    std::vector<ContactConstraint> contacts;   // filter: the part's constraints
  };
  // The grid of the build at positions x (serial), then candidatesOf over the triangles.
  void buildCandidates(const double* x, const double* w, SweepTeam* team);
  // Candidates of triangles [f_begin, f_end) into part.candidates / part.distance.
  void candidatesOf(int f_begin, int f_end, const double* x, const double* w, Part& part) const;
  // Constraints of candidates [e_begin, e_end) into part.contacts.
  void filterCandidates(size_t e_begin, size_t e_end, const double* x_start, const double* x_pred,
                        Part& part) const;

  ContactOptions options_;
  Eigen::MatrixXi F_;
  std::vector<double> rest_;  // 3 #V rest positions
  double min_cell_size_ = 1.0;
  // Dense grid of the last build: cell_start_ (#cells + 1) into sorted_ (#V vertex ids sorted
  // by cell), sorted_x_ their positions and sorted_rest_ their rest positions (3 #V each, same
  // order), cell_ each vertex's cell id.
  std::vector<int> cell_start_, sorted_, cell_;
  std::vector<double> sorted_x_, sorted_rest_;
  // Verlet list: (triangle, vertex) pairs, their distance at the build, and the positions
  // they were built from; moved_ is each vertex's displacement since the build (per step).
  std::vector<std::pair<int, int>> candidates_;
  std::vector<double> candidate_distance_;
  std::vector<double> x_built_, moved_;
  // The build's grid (set by buildCandidates, read by candidatesOf).
  Eigen::Vector3d grid_lo_ = Eigen::Vector3d::Zero();
  double inv_cell_ = 1.0;
  int dims_[3] = {1, 1, 1};
  std::vector<Part> parts_;  // one per thread
  int rebuilds_ = 0;
};

}  // namespace chordfit
