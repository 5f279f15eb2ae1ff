// A case from a bare open-state mitral valve mesh (segmented elsewhere, e.g. 3D Slicer or
// SlicerHeart) and three landmarks, so a user does not have to write the annulus ring and the
// per-vertex leaflet labels by hand:
//   1. annulus ring: the mesh boundary loop nearest to the two commissure landmarks (each
//      within kMaxLandmarkDistanceMm of it), in the loop's own order;
//   2. commissures: the ring vertices nearest to the landmarks; they split the ring into two
//      arcs, and the arc holding the ring vertex nearest to the anterior landmark (within
//      kMaxAnteriorLandmarkDistanceMm of it) is the anterior leaflet's (commissure vertices go
//      with it); every landmark must be a finite point;
//   3. leaflet labels: each vertex takes the leaflet whose annulus arc is nearer along the mesh
//      edges (graph_distance.h);
//   4. closed annulus: a closed-state annulus curve, if given, resampled onto the ring with both
//      commissures anchored (each at the curve point nearest to its open position) and each arc
//      mapped by arc length, in the direction that keeps the ring nearer to its open position;
//      without one the annulus stays at its open position (static).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"

namespace chordfit {

constexpr double kMaxLandmarkDistanceMm = 5.0;
// The anterior landmark only picks which arc is the anterior leaflet's, so it may sit looser
// than a commissure (a point of the anterior annulus placed by eye); farther than this from
// every ring vertex it is not on this annulus (another file, unit or a typo: 1e308 used to
// pick an arbitrary arc).
constexpr double kMaxAnteriorLandmarkDistanceMm = 10.0;

struct ImportLandmarks {
  Eigen::Vector3d anterolateral;  // anterolateral commissure, on the annulus
  Eigen::Vector3d posteromedial;  // posteromedial commissure, on the annulus
  Eigen::Vector3d anterior;       // a point of the anterior annulus, e.g. its midpoint
};

// The input an import error is about, so that a command names the file (or option) that gave
// it rather than always the mesh.
enum class ImportInput { kMesh, kLandmarks, kClosedAnnulus };

struct ImportedCase {
  ValveCase valve_case;  // name, mesh (V, F, leaflet labels, annulus), annulus_closed
  std::string error;     // non-empty: what is wrong with the input, in words
  ImportInput error_input = ImportInput::kMesh;  // which input `error` is about
  // With kLandmarks: the landmarks at fault, 0-based in ImportLandmarks' order (AL, PM, anterior).
  std::vector<int> error_landmarks;
  double commissure_distance_mm[2] = {0.0, 0.0};  // landmark to its ring vertex (AL, PM)
  double anterior_fraction = 0.0;                 // anterior arc / ring perimeter (open state)
  double closed_shift_mm = 0.0;                   // mean ring displacement open -> closed
  // Boundary loops besides the annulus ring and the leaflets' free edge (the orifice): holes.
  int holes = 0;
  bool ok() const { return error.empty(); }
};

// V #V by 3 open-state positions (mm, LPS), F #F by 3 triangles; `closed_curve` #P by 3 points
// of the closed-state annulus as a closed loop (empty: static annulus).
ImportedCase importValveCase(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                             const ImportLandmarks& landmarks, const Eigen::MatrixXd& closed_curve,
                             const std::string& name);

}  // namespace chordfit
