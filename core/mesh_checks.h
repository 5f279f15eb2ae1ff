// Validation of meshes and of the annulus ring against the mesh. Each check reports every
// problem it finds (capped per kind, with a count of the rest) to a Diagnostics.
#pragma once

#include <string>

#include <Eigen/Core>

#include "core/diagnostics.h"

namespace chordfit {

// Checks a triangle mesh read from `file`:
//   - every face index in [0, #V)
//   - every coordinate finite (no NaN / infinity)
//   - no zero-area (degenerate) triangle, relative to the mesh size (unless `check_areas` is
//     false: a caller that found the mesh's size absurd, where that tolerance would call
//     every real triangle degenerate)
//   - no non-manifold edge (an edge shared by more than two triangles)
// Returns true when the mesh passed every check.
bool checkMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const std::string& file,
               Diagnostics& diagnostics, bool check_areas = true);

// Checks that `ring` is a closed loop of boundary vertices of F: at least 3 distinct
// in-range vertices, and every consecutive pair (last -> first included) joined by a
// boundary edge (an edge of exactly one triangle). `file`/`where` name the ring's source.
bool checkAnnulusRing(const Eigen::MatrixXi& F, int vertex_count, const Eigen::VectorXi& ring,
                      const std::string& file, const std::string& where, Diagnostics& diagnostics);

}  // namespace chordfit
