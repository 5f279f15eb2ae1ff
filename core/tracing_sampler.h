// Synthetic echo tracings of a closed valve (DESIGN §3 "Tracings", §8): what an echo reader
// draws on a few long-axis views, made from a known closed mesh.
//   1. planes: K long-axis planes through the closed annulus centre c, each containing the
//      annulus-plane normal n, evenly rotated about n: plane i contains the in-plane direction
//      d_i = cos(phi_i) a + sin(phi_i) l, phi_i = i pi / K, and has normal n x d_i; plane 0 is
//      the anteroposterior plane (a = anterior axis, l = anterolateral axis, annulus_plane.h);
//   2. section: the mesh cut by each plane, chained into polylines, split where the leaflet
//      label of the cut triangles changes;
//   3. resampling every `spacing_mm` of arc length (both ends kept);
//   4. dropout: `dropout_fraction` of the total traced length removed in `dropout_pieces`
//      contiguous gaps of equal length at uniformly random, non-overlapping places (echo
//      dropout); a polyline is split at a gap and pieces with fewer than 2 points vanish;
//   5. noise: every point moves by sigma (g1 d_i + g2 n), g1, g2 standard normal, i.e.
//      isotropic Gaussian noise within the image plane (an echo reader's hand is in-plane).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/annulus_plane.h"
#include "core/case_data.h"
#include "core/cohort_presets.h"

namespace chordfit {

// A long-axis image plane with its in-plane axes: u = d_i (horizontal in pictures), w = n.
struct ImagePlane {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  // unit
  Eigen::Vector3d u = Eigen::Vector3d::UnitX();       // unit, in plane
  Eigen::Vector3d w = Eigen::Vector3d::UnitZ();       // unit, in plane (= n_AP)
  double angle = 0.0;                                 // phi_i, rad
};

// K planes about the frame (step 1). K >= 1.
std::vector<ImagePlane> longAxisPlanes(const AnnulusFrame& frame, int count);

// The distinct image planes of `tracings` (tracedOnPlane; normals of either sign), in
// order of first appearance, with in-plane axes w = the component of the closed annulus normal
// `frame.plane.normal` within the plane (up, toward the atrium) and u = normal x w, and
// `angle` = the angle of u from the anteroposterior axis frame.a about the annulus normal, in
// [0, pi). The origin and normal are the first such tracing's, as given (tracings carry unit
// normals, case_io.h). For planes made by longAxisPlanes this returns the same planes
// (u = d_i).
std::vector<ImagePlane> tracingPlanes(const std::vector<Tracing>& tracings,
                                      const AnnulusFrame& frame);

// Whether tracing t was drawn on `plane`: unit normals of either sign within 1e-3 rad, and
// t's origin within 0.01 mm of the plane (one plane written by different tools).
bool tracedOnPlane(const Tracing& t, const ImagePlane& plane);

// A polyline cut out of a mesh, with the leaflet of the triangles it crosses.
struct SectionPolyline {
  Eigen::MatrixXd points;  // #P by 3, #P >= 2
  int leaflet = -1;
};

// Leaflet of each face: the label most of its three vertices carry (ties: the smallest).
//   F  #F by 3,  vertex_leaflet  #V.  Returns #F labels.
Eigen::VectorXi faceLeaflets(const Eigen::MatrixXi& F, const Eigen::VectorXi& vertex_leaflet);

// The section of the triangle mesh (V, F) by the plane (origin, normal) (step 2). Vertices
// are classified by the sign of their signed distance (>= 0 counts as positive), so every cut
// triangle contributes one segment between two edge crossings, and segments chain through
// shared edges. Polylines are split where the face leaflet changes. Deterministic order: by
// the smallest face index of each chain.
//   V  #V by 3,  F  #F by 3,  face_leaflet  #F (e.g. faceLeaflets)
std::vector<SectionPolyline> planeSection(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                          const Eigen::VectorXi& face_leaflet,
                                          const Eigen::Vector3d& origin,
                                          const Eigen::Vector3d& normal);

// Points every `spacing` of arc length along P (#P by 3), both ends kept; the last interval is
// whatever remains (> 0). spacing > 0.
Eigen::MatrixXd resamplePolyline(const Eigen::MatrixXd& P, double spacing);

struct TracingSamplerOptions {
  int planes = 6;
  double spacing_mm = 0.5;
  double noise_mm = 0.3;          // sigma of the in-plane Gaussian noise
  double dropout_fraction = 0.1;  // of the traced length, in [0, 1) (make-case: at most 0.9)
  int dropout_pieces = 0;         // gaps; <= 0 selects max(1, round(planes / 2))
};

// Tracings of the closed mesh (steps 1-5), one Tracing per surviving polyline, with the plane's
// origin and normal and the polyline's leaflet. `frame` is the closed annulus frame
// (metrics.h closedAnnulus). Draws from `random` in a fixed order (dropout places, then noise
// in point order).
std::vector<Tracing> sampleTracings(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                    const Eigen::VectorXi& vertex_leaflet,
                                    const AnnulusFrame& frame, const TracingSamplerOptions& options,
                                    SeededRandom& random);

}  // namespace chordfit
