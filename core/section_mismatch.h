// The converse of the Table 1 deviation: how far the closed mesh, cut by the tracing planes,
// strays from what was traced there.
//
// The deviation (metrics.h) measures every tracing point to the mesh, so tissue lying where
// nothing was traced costs nothing. A fit can then park a prolapsing flap flat over the valve
// centre, through planes whose tracings show no tissue there (docs/fitting.md, "Section
// term"): the tracings of the flap are near it, the planes that cut the flap elsewhere are
// not asked. This measure asks them: for every tracing plane and leaflet L,
//
//   E(plane, L) = (1 / h) * integral over the sections of L's faces by the plane of
//                 min(max(0, d(s) - tolerance), cap)^2 ds,
//
// d(s) = distance from the section point s to the nearest tracing segment of L on that plane
// (segments between consecutive points of one tracing; unlabelled tracings count for every
// leaflet), h = 0.5 mm (the tracing sample spacing, so that 0.5 mm of section weighs as much
// as one tracing point). The tolerance lets noise and small dropout gaps pass free; the cap
// bounds what one stray piece can cost (a misregistered plane). A plane without a tracing of
// L gives E = 0: nothing is known there.
//
// The integral is exact in the section geometry and continuous in the mesh positions: each
// section segment (one cut triangle) is integrated by 3-point Gauss-Legendre, so a segment
// that appears when a vertex crosses the plane enters with zero length.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"

namespace chordfit {

struct SectionMismatchOptions {
  double tolerance_mm = 1.5;  // ~5 tracing noise SDs (0.3 mm) plus a short dropout gap
  double cap_mm = 5.0;
  double unit_length_mm = 0.5;  // h above
};

class SectionMismatch {
 public:
  // The distinct tracing planes of the case and their tracing segments, by leaflet.
  SectionMismatch(const ValveCase& valve_case, const SectionMismatchOptions& options = {});

  // planes x leaflets; E in that order (plane-major). 0 when the case has no tracings.
  int termCount() const { return static_cast<int>(planes_.size()) * leaflets_; }
  int planeCount() const { return static_cast<int>(planes_.size()); }

  // E(plane, leaflet) of the closed state V (#V by 3, the case mesh's topology), mm^2 / mm.
  Eigen::VectorXd excess(const Eigen::MatrixXd& V) const;

 private:
  struct Plane {
    Eigen::Vector3d origin, normal;
    // Per leaflet: tracing segments as (#S by 6) rows [a, b].
    std::vector<Eigen::MatrixXd> segments;
  };
  Eigen::MatrixXi F_;
  Eigen::VectorXi face_leaflet_;
  int leaflets_ = 0;
  SectionMismatchOptions options_;
  std::vector<Plane> planes_;
};

}  // namespace chordfit
