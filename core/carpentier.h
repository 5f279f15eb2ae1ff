// Carpentier segments (A1-A3, P1-P3): each leaflet's stretch of annulus between its two
// commissures is split into three equal angular thirds, numbered from the anterolateral
// commissure (segment 1) to the posteromedial one (segment 3) (Carpentier's nomenclature,
// Carpentier A. "Cardiac valve surgery - the French correction", J Thorac Cardiovasc Surg
// 1983;86:323). A point belongs to the segment of its leaflet whose angular range, seen
// along the annulus-plane normal from the annulus centre, contains it.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/annulus_plane.h"
#include "core/valve_mesh.h"

namespace chordfit {

struct LeafletArc {
  int leaflet = 0;
  double theta_start = 0.0;  // angle (rad) of the end nearer the anterolateral side
  double sweep = 0.0;        // signed angular extent from theta_start to the other end
  // For closedSegmentOf, in the frame's in-plane coordinates (a, l) about the centre: the
  // commissures at fraction 0 and 1, and the ring points at 1/3 and 2/3 of the sweep.
  Eigen::Vector2d commissure_start = Eigen::Vector2d::Zero();
  Eigen::Vector2d commissure_end = Eigen::Vector2d::Zero();
  Eigen::Vector2d ring_third[2] = {Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
};

struct SegmentMap {
  AnnulusFrame frame;
  std::vector<LeafletArc> arcs;            // one per leaflet present on the ring
  std::vector<std::string> leaflet_names;  // copied from the mesh
};

// Builds the map from the annulus ring at `ring_positions` (#ring by 3, ordered as
// mesh.annulus; e.g. the closed annulus) with leaflet labels mesh.leaflet(mesh.annulus).
// Commissures are where the ring's leaflet label changes.
SegmentMap buildSegmentMap(const Eigen::MatrixXd& ring_positions, const ValveMesh& mesh,
                           const AnnulusFrame& frame);

// The map of the open state: the ring at its open positions in the open annulus frame
// (openAnnulusFrame), as the prolapse measure, the cord layout and the lesion tissue localise.
SegmentMap openStateSegmentMap(const ValveMesh& mesh);

// Angle of p around the annulus centre in the frame's plane: atan2(l.(p-c), a.(p-c)).
double annulusAngle(const AnnulusFrame& frame, const Eigen::Vector3d& p);

// Where p lies along its leaflet's arc: `fraction` in [0, 1] from the anterolateral end
// (clamped to the arc), on leaflet `leaflet`, or on the leaflet whose arc contains the point's
// angle if leaflet < 0. A labelled point more than 45 degrees beyond its own arc but inside it
// seen from the opposite side has crossed the valve centre and is placed on that side.
// leaflet = -1 when the leaflet has no arc.
struct ArcPosition {
  int leaflet = -1;
  double fraction = 0.0;
};
ArcPosition arcPositionOf(const SegmentMap& map, const Eigen::Vector3d& p, int leaflet);

// Segment index 0..2 of point p on leaflet `leaflet` (clamped to the leaflet's ends).
// If leaflet < 0 the leaflet whose arc contains the point's angle is used.
// Returns a global segment id = leaflet * 3 + index, or -1 if the leaflet has no arc.
int segmentOf(const SegmentMap& map, const Eigen::Vector3d& p, int leaflet);

// Segment id (as segmentOf) of a point of the CLOSED valve on leaflet `leaflet` (< 0: the
// leaflet whose arc contains its angle), localised as the tracing reader and 3D echo
// segmentation do: Carpentier's segments run from the annulus to the free edge, and in the
// closed valve the free edges lie along the coaptation line between the commissures. So the
// boundary between segments k and k + 1 is the straight line, in the annulus plane, from the
// ring point at (k + 1)/3 of the leaflet's arc to the point at (k + 1)/3 of the chord between
// its commissures (the coaptation line's straight approximation). segmentOf's rays from the
// centre agree at the annulus but not near the coaptation line, where every point lies near
// the commissure-to-commissure axis: a P2 flap billowing over the centre, cut by a plane 60 or
// 90 degrees off the anteroposterior axis, would be read as P1 or P3. Falls back to segmentOf
// for a leaflet that goes all round (no commissures).
int closedSegmentOf(const SegmentMap& map, const Eigen::Vector3d& p, int leaflet);

// "A2", "P1", ...: first letter of the leaflet name, upper-cased, + (index + 1).
std::string segmentName(const std::vector<std::string>& leaflet_names, int segment_id);
std::string segmentName(const SegmentMap& map, int segment_id);

}  // namespace chordfit
