#include "core/annulus_plane.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

namespace chordfit {

Plane fitPlane(const Eigen::MatrixXd& P) {
  Plane plane;
  plane.centre = P.colwise().mean().transpose();
  const Eigen::MatrixXd centred = P.rowwise() - plane.centre.transpose();
  const Eigen::Matrix3d covariance = centred.transpose() * centred;
  // Eigenvalues come sorted ascending: column 0 spans the direction of least spread.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  plane.normal = solver.eigenvectors().col(0).normalized();
  return plane;
}

namespace {

Eigen::MatrixXd ringPositions(const ValveMesh& mesh) {
  Eigen::MatrixXd ring(mesh.annulus.size(), 3);
  for (Eigen::Index i = 0; i < mesh.annulus.size(); ++i) ring.row(i) = mesh.V.row(mesh.annulus(i));
  return ring;
}

// In-plane unit vector from the plane centre toward the ring points labelled with leaflet 0.
Eigen::Vector3d anteriorAxis(const Eigen::MatrixXd& ring, const ValveMesh& mesh,
                             const Plane& plane) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (Eigen::Index i = 0; i < mesh.annulus.size(); ++i) {
    if (mesh.leaflet(mesh.annulus(i)) != 0) continue;
    sum += ring.row(i).transpose();
    ++count;
  }
  Eigen::Vector3d towards = count > 0 ? Eigen::Vector3d(sum / count - plane.centre)
                                      : Eigen::Vector3d(ring.row(0).transpose() - plane.centre);
  towards -= plane.normal.dot(towards) * plane.normal;
  if (towards.norm() < 1e-12) {
    // Degenerate: leaflet 0 centred on the annulus centre. Any in-plane axis will do.
    towards = plane.normal.unitOrthogonal();
  }
  return towards.normalized();
}

AnnulusFrame frameFrom(const Plane& plane, const Eigen::MatrixXd& ring, const ValveMesh& mesh) {
  AnnulusFrame frame;
  frame.plane = plane;
  frame.a = anteriorAxis(ring, mesh, plane);
  frame.l = plane.normal.cross(frame.a).normalized();
  return frame;
}

}  // namespace

AnnulusFrame openAnnulusFrame(const ValveMesh& mesh) {
  const Eigen::MatrixXd ring = ringPositions(mesh);
  Plane plane = fitPlane(ring);
  // Leaflets hang into the ventricle in the open state: the atrial side is where they are not.
  const double mean_signed = ((mesh.V.rowwise() - plane.centre.transpose()) * plane.normal).mean();
  if (mean_signed > 0.0) plane.normal = -plane.normal;
  return frameFrom(plane, ring, mesh);
}

AnnulusFrame annulusFrameFromRing(const Eigen::MatrixXd& ring_positions, const ValveMesh& mesh,
                                  const AnnulusFrame& reference) {
  Plane plane = fitPlane(ring_positions);
  if (plane.normal.dot(reference.plane.normal) < 0.0) plane.normal = -plane.normal;
  return frameFrom(plane, ring_positions, mesh);
}

}  // namespace chordfit
