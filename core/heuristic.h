// The paper's heuristic chordae model (Walczak et al., "Modeling of tendinous cords"), plus the
// automatic placement of cord leaflet vertices that the paper leaves as future work.
//   - annulus plane (AP) by PCA, n_AP toward the atrium (annulus_plane.h);
//   - cord vertices: given, or primary cords on the free edge at a regular spacing and
//     secondary cords on the belly;
//   - subsets per PM tip: side of the plane through the annulus centre spanned by n_AP and
//     the anteroposterior axis (anterolateral +l, posteromedial -l);
//   - tip_i = c_i - d_i n_AP, c_i the centroid of subset i, d_i = dist(c_i, AP);
//   - rest length l0 = dist(V_j, AP) + |V_j - tip_i|, in the open state.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/annulus_plane.h"
#include "core/case_data.h"
#include "core/cordset.h"

namespace chordfit {

struct HeuristicOptions {
  double primary_spacing_mm = 4.0;    // arc length between primary cords along the free edge
  double secondary_spacing_mm = 6.0;  // spacing of secondary cords along the belly
  double secondary_depth_mm = 7.0;    // secondary cords this far (edge path) from the free edge
  // No cord where the leaflet is shorter than this from annulus to the vertex (commissures).
  double min_annulus_distance_mm = 4.0;
  // Elastic cords per kind (issue 3's "elastic option per cord kind"), mm/N: 0 is the paper's
  // inextensible cord. For the cords placed here; a case's own cords keep theirs.
  double primary_compliance_mm_per_n = 0.0;
  double secondary_compliance_mm_per_n = 0.0;
};

// The finest cord spacing the automatic placement takes, mm (the defaults are 4 and 6). Below
// the edges of any mesh the project makes (make-case refuses edges under 1 mm) a finer spacing
// places no more cords, only more targets on the same vertices; and far below it the count of
// targets overflows an int (1e-9 mm once asked for 21 GB of angular bins).
constexpr double kMinCordSpacingMm = 0.1;

// round(length / spacing), the count of cords `spacing` apart along a line of `length`, in
// double before the cast. Throws std::invalid_argument naming `what` for a spacing below
// kMinCordSpacingMm or not finite, or a count beyond any mesh's vertices (a length that is
// not finite or absurd), rather than return a wrapped count.
int spacedCordCount(double length, double spacing, const char* what);

struct CordAttachment {
  int vertex = 0;
  CordKind kind = CordKind::kPrimary;
  std::optional<CordPoint> point;  // a case cord's insertion between vertices (cordset.h)
};

// Free-edge loops: boundary loops of the mesh other than the annulus ring.
std::vector<std::vector<int>> freeEdgeLoops(const ValveMesh& mesh);

// Automatic placement of cord leaflet vertices (primaries first, then secondaries), in a
// deterministic order. Throws std::invalid_argument for spacings spacedCordCount refuses.
std::vector<CordAttachment> placeCordAttachments(const ValveMesh& mesh,
                                                 const HeuristicOptions& options);

// Tip subset of each vertex: 0 (anterolateral, l.(p - c) >= 0) or 1 (posteromedial).
std::vector<int> splitBySide(const ValveMesh& mesh, const AnnulusFrame& frame,
                             const std::vector<int>& vertices);

// Paper's tip: c - d n_AP for the centroid c of the insertion `points` (d = |dist(c, AP)|).
Eigen::Vector3d heuristicTipPosition(const Plane& annulus_plane,
                                     const std::vector<Eigen::Vector3d>& points);

// Paper's rest length: dist(p, AP) + |p - tip|.
double heuristicRestLength(const Eigen::Vector3d& p, const Plane& annulus_plane,
                           const Eigen::Vector3d& tip);

// The heuristic cord set of a case. Cord vertices (and points), kinds and tip subsets come from the
// case's cords when it has them (the user's choice), else from automatic placement and
// the side split; tip positions come from the case's pm_tips when given (with the case's cords
// only when pmTipsCountProblem is empty: the tips pair by their place in the list), else from
// the paper's formula. Rest lengths always from the paper's formula; every cord has
// provenance heuristic, scale 1 and the case cord's compliance (0 otherwise).
CordSet heuristicCordSet(const ValveCase& valve_case, const HeuristicOptions& options = {});

// Why heuristicCordSet cannot use the case's pm_tips, or "" when it can (or there are none).
// With the case's own cords, each cord-set tip takes the position (and name) of the pm_tips tip
// in the same place in the list, so the counts must match; with another count pm_tips was
// ignored without a word and the paper's formula placed the tips. Without cords any count
// works (each placed cord goes to the nearest tip).
std::string pmTipsCountProblem(const ValveCase& valve_case);

}  // namespace chordfit
