// Mesh readers and writers.
//   read:  PLY (ascii + binary), OBJ, STL (ascii + binary) through CGAL's polygon-soup I/O;
//          legacy VTK polydata (ascii + binary, classic POLYGONS and VTK>=9 OFFSETS/
//          CONNECTIVITY layouts) by a small parser, since CGAL reads VTK only through VTK.
//   write: PLY (binary little endian) and legacy VTK polydata (ascii), each with named
//          per-vertex scalar fields (float vertex properties in the PLY, POINT_DATA arrays in
//          the VTK). For colouring by them, the VTK is the safe choice: ParaView's PLY reader
//          has been reported to skip extra vertex properties (docs/outputs.md).
// The format is chosen by the file extension (case-insensitive). Readers never throw on bad
// content: they add "file: where: problem" entries to the Diagnostics and return false.
// Readers do not validate the mesh (indices, degeneracy, manifoldness): see mesh_checks.h.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/diagnostics.h"

namespace chordfit {

struct VertexScalarField {
  std::string name;        // e.g. "deviation_mm"; spaces are replaced by '_' on write
  Eigen::VectorXd values;  // #V values; NaN marks "undefined here"
};

// Reads triangles (polygons with more than 3 corners are fan-triangulated). Quads etc. are
// accepted; lines and points are ignored. `display_name` is used in messages.
bool readMesh(const std::filesystem::path& path, Eigen::MatrixXd& V, Eigen::MatrixXi& F,
              Diagnostics& diagnostics, const std::string& display_name = "");

// Writes atomically. Throws std::runtime_error on an unknown extension or I/O failure.
void writePly(const std::filesystem::path& path, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
              const std::vector<VertexScalarField>& scalars = {});
void writeVtk(const std::filesystem::path& path, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
              const std::vector<VertexScalarField>& scalars = {});

}  // namespace chordfit
