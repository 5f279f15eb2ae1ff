// Anatomical cord attachments: where a cord inserts on a leaflet, said in anatomy rather than
// in vertex indices, so that one patient's cords can be placed on meshes of any resolution and
// stay in one-to-one correspondence (the synthetic cohort simulates its truth on a finer mesh
// than the case it writes; DESIGN §8, "inverse crime").
//
// An attachment is (leaflet, fraction, depth):
//   fraction  position along the leaflet's annulus arc, 0 at the anterolateral commissure,
//             1 at the posteromedial one, measured as the polar angle about the annulus
//             centre in the open annulus plane (the angle Carpentier segments are cut by,
//             core/carpentier.h), so segment = floor(3 fraction);
//   depth     distance from the free edge along the leaflet's meridian, mm (0 = primary cord
//             on the free edge; ~7 mm = secondary cord on the belly, as the heuristic).
// It is realised on a parametric valve (core/parametric_valve.h) by interpolating between the
// meridian columns that bracket the fraction, and then snapped to the nearest mesh vertex.
// The commissures are the mesh ring's (midpoints of the ring edges where the leaflet label
// changes, as core/carpentier.h), so one fraction lands within about half a ring edge of the
// same anatomical place on meshes of different resolution, well inside the snapping error.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/cordset.h"
#include "core/parametric_valve.h"

namespace chordfit {

struct AnatomicalAttachment {
  int leaflet = 0;
  double fraction = 0.5;  // 0 anterolateral commissure .. 1 posteromedial commissure
  double depth_mm = 0.0;  // from the free edge along the meridian
  CordKind kind = CordKind::kPrimary;
  // PM tip: 0 anterolateral (fraction <= 0.5), 1 posteromedial; the paper's split by side of
  // the anteroposterior plane, decided anatomically so it cannot differ between meshes.
  int tip = 0;
  // Carpentier segment id leaflet * 3 + min(2, floor(3 fraction)).
  int segment() const;
};

struct AttachmentLayoutOptions {
  double primary_spacing_mm = 4.0;    // along the free edge (heuristic.h default)
  double secondary_spacing_mm = 6.0;  // along the belly line
  double secondary_depth_mm = 7.0;    // belly line distance from the free edge
  // No cord closer than this to the annulus (short commissural and cleft tissue).
  double min_annulus_distance_mm = 4.0;
};

// The patient's cord layout, decided once on one realisation of the anatomy (use the finest
// mesh). Per leaflet: n_p = max(1, round(free-edge length / primary spacing)) primaries at
// fractions (i + 1/2) / n_p; n_s = round(belly-line length / secondary spacing) secondaries
// at (i + 1/2) / n_s, dropping those where the leaflet is shorter than depth + the minimum
// annulus distance. Order: anterior primaries, posterior primaries, anterior secondaries,
// posterior secondaries, each by increasing fraction.
std::vector<AnatomicalAttachment> layoutAttachments(const ParametricValve& valve,
                                                    const AttachmentLayoutOptions& options = {});

// Position on the valve surface of an anatomical location (open state). Throws
// std::invalid_argument if the valve has no column on that leaflet.
Eigen::Vector3d attachmentPoint(const ParametricValve& valve, int leaflet, double fraction,
                                double depth_mm);

// Leaflet height (annulus to free edge along the meridian, mm) at a fraction of its arc.
double leafletHeightAt(const ParametricValve& valve, int leaflet, double fraction);

// One vertex per attachment, same order: the nearest vertex of the attachment's leaflet to
// attachmentPoint, excluding annulus ring vertices (Dirichlet, a cord there does nothing) and
// vertices already taken by an earlier attachment, so the map is one to one even on coarse
// meshes. Throws std::invalid_argument when a leaflet runs out of vertices.
std::vector<int> mapAttachments(const ParametricValve& valve,
                                const std::vector<AnatomicalAttachment>& attachments);

// One point per attachment, same order: the point of the attachment's leaflet surface
// (triangles whose three vertices carry its label) nearest to attachmentPoint, as barycentric
// weights on that triangle; triangles touching the annulus ring are left out. Unlike mapAttachments
// this carries no snapping error: on meshes of any resolution the cord inserts where the anatomy
// says, up to the distance between the meshes' surfaces (their chordal sag, well under 0.1 mm).
// Throws std::invalid_argument when a leaflet has no triangle.
std::vector<CordPoint> pointAttachments(const ParametricValve& valve,
                                        const std::vector<AnatomicalAttachment>& attachments);

// The vertex of a point's largest weight (its cord's `vertex`, cordset.h).
int largestWeightVertex(const CordPoint& point);

// A CordSet skeleton for heuristicCordSet: tips "anterolateral" / "posteromedial" (positions
// unset) and one cord per attachment with its vertex, kind and tip.
CordSet attachmentCordSet(const std::vector<AnatomicalAttachment>& attachments,
                          const std::vector<int>& vertices);
// The same with the cords inserting at `points` (vertex: each point's largest weight).
CordSet attachmentCordSet(const std::vector<AnatomicalAttachment>& attachments,
                          const std::vector<CordPoint>& points);

}  // namespace chordfit
