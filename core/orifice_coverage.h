// Is the closed valve closed? The fraction of the orifice that the leaflets cover, seen along
// the annulus-plane normal: the closed annulus ring and every leaflet triangle are projected
// onto the closed annulus plane, and the orifice (the area inside the projected ring) is
// sampled on a square grid. 1 = no gap; 1 - coverage of the orifice area is the open
// (regurgitant) area, a geometric proxy of the anatomic regurgitant orifice area that
// planimetry of an en-face (surgeon's) view measures.
//
// The mesh is the leaflets' mid-surface; the tissue extends half its thickness to either side,
// and the contact model keeps two coapting mid-surfaces one thickness apart (simulator.h). So
// the mid-surfaces of a coaptation curtain, both nearly parallel to the annulus normal,
// project to two lines a thickness apart with an open strip between them, where the tissue
// itself closes the orifice. With tissue_radius_mm = half the thickness, the covered region
// is the projection of the thickened sheet (the mid-surface swept by a ball of that radius:
// every projected triangle grown by the radius), and the strip closes.
//
// A projection does not see heights: tissue folded over a gap (a flail flap lying across the
// orifice) covers it, and so does a leaflet that overlaps the other without touching it. The
// proxy is meant for what it shows on a coapting valve: gaps between the free edges, such as
// paracommissural gaps left by tethered scallops.
#pragma once

#include <Eigen/Core>

#include "core/annulus_plane.h"

namespace chordfit {

struct OrificeCoverage {
  double orifice_area_mm2 = 0.0;  // area inside the projected closed ring
  double open_area_mm2 = 0.0;     // part of it no leaflet triangle covers
  int samples = 0;                // grid points inside the ring
  double tissue_radius_mm = 0.0;  // the half-thickness the triangles were grown by
  // Covered fraction of the orifice, 0..1; NaN when the ring encloses no grid point.
  double coverage() const;
};

// ring      #ring by 3 closed annulus positions, in ring order
// V, F      closed mesh (every triangle counts, whatever its leaflet)
// frame     the closed annulus frame (plane and in-plane axes a, l)
// grid_mm   sample spacing; the result is exact for the sampled points, and the areas are
//           sample counts times the spacing squared. Coarsened when the ring's bounding box
//           would need more than 4 million samples.
// tissue_radius_mm  a sample within this distance of a projected triangle is covered (see
//           above; 0 = the bare mid-surface)
OrificeCoverage orificeCoverage(const Eigen::MatrixXd& ring, const Eigen::MatrixXd& V,
                                const Eigen::MatrixXi& F, const AnnulusFrame& frame,
                                double grid_mm = 0.25, double tissue_radius_mm = 0.0);

}  // namespace chordfit
