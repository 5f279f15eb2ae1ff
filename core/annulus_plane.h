// Annulus plane (AP) and the anatomical frame built on it (DESIGN §5).
#pragma once

#include <Eigen/Core>

#include "core/valve_mesh.h"

namespace chordfit {

// The z component of (u, 0) x (v, 0): twice the signed area of the triangle u, v span,
// positive when v lies counter-clockwise of u.
inline double cross2d(const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
  return u.x() * v.y() - u.y() * v.x();
}

struct Plane {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit
  double signedDistance(const Eigen::Vector3d& p) const { return normal.dot(p - centre); }
};

// Least-squares plane of a point set by PCA: centre = centroid, normal = eigenvector of the
// smallest eigenvalue of the covariance. The sign of the normal is arbitrary here.
// P  #P by 3, #P >= 3 and not collinear.
Plane fitPlane(const Eigen::MatrixXd& P);

// The valve's anatomical frame:
//   n  annulus-plane normal, pointing toward the atrium. In the open state the leaflets hang
//      from the annulus into the ventricle, so n is chosen with the leaflet vertices' mean
//      signed distance negative.
//   a  anterior axis: in-plane unit vector from the annulus centre toward the centroid of the
//      annulus vertices of leaflet 0 (mitral: the anterior leaflet).
//   l  = n x a. In the surgeon's atrial view (anterior leaflet up) +l is the viewer's left,
//      the anterolateral side; -l is posteromedial.
struct AnnulusFrame {
  Plane plane;
  Eigen::Vector3d a = Eigen::Vector3d::UnitX();
  Eigen::Vector3d l = Eigen::Vector3d::UnitY();
};

// Frame of the open-state mesh (annulus ring of `mesh`, positions mesh.V).
AnnulusFrame openAnnulusFrame(const ValveMesh& mesh);

// Frame of a deformed state: plane fitted to `ring_positions` (#ring by 3, ordered as
// mesh.annulus), normal oriented to agree with `reference.plane.normal`, anterior axis from
// the ring points of leaflet 0.
AnnulusFrame annulusFrameFromRing(const Eigen::MatrixXd& ring_positions, const ValveMesh& mesh,
                                  const AnnulusFrame& reference);

}  // namespace chordfit
