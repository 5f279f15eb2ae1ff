// The valve surface as plain Eigen matrices (libigl style). Derived structures (edges,
// boundary loops, normals, areas) come from free functions in mesh_topology.h / geometry.h.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace chordfit {

struct ValveMesh {
  Eigen::MatrixXd V;        // #V by 3 vertex positions, mm
  Eigen::MatrixXi F;        // #F by 3 triangle vertex indices into V
  Eigen::VectorXi leaflet;  // #V leaflet label per vertex, index into leaflet_names
  // Names of the leaflets, by label. Mitral default: {"anterior", "posterior"}.
  std::vector<std::string> leaflet_names{"anterior", "posterior"};
  Eigen::VectorXi annulus;  // ordered loop of vertex indices on the mesh boundary
};

}  // namespace chordfit
