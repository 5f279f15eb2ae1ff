// The only door to CGAL. CGAL's headers are slow to compile, so every use of CGAL lives in
// cgal_backend.cpp behind these plain-Eigen functions.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include <Eigen/Core>

namespace chordfit {

// Reads a polygon soup (PLY, OBJ, STL, OFF) with CGAL::IO::read_polygon_soup and
// fan-triangulates polygons. STL soups are welded (duplicate points merged).
// Returns false with a short reason in `error` on failure.
bool cgalReadTriangleSoup(const std::filesystem::path& path, Eigen::MatrixXd& V, Eigen::MatrixXi& F,
                          std::string& error);

// Merges vertices at exactly the same position (CGAL Polygon_mesh_processing::
// merge_duplicate_points_in_polygon_soup), as exporters that write each triangle with its own
// three corners leave them; the faces are renumbered. Returns the number of vertices merged
// away (0: V and F unchanged). V must be finite and F's indices within V.
int weldCoincidentVertices(Eigen::MatrixXd& V, Eigen::MatrixXi& F);

// Exact point-to-triangle-mesh distances with a CGAL AABB tree.
class SurfaceDistance {
 public:
  // V #V by 3, F #F by 3 (degenerate triangles are skipped).
  SurfaceDistance(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
  ~SurfaceDistance();
  SurfaceDistance(const SurfaceDistance&) = delete;
  SurfaceDistance& operator=(const SurfaceDistance&) = delete;

  // Unsigned distance from p to the closest point of the surface, and that point.
  double distance(const Eigen::Vector3d& p, Eigen::Vector3d* closest = nullptr) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Number of pairs of non-adjacent triangles that intersect (CGAL
// Polygon_mesh_processing::self_intersections on a Surface_mesh; a box-intersection search
// on the soup when F is not a polygon mesh). Returns -1 for an out-of-range index, a
// non-finite coordinate, or a CGAL failure.
int countSelfIntersections(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);

}  // namespace chordfit
