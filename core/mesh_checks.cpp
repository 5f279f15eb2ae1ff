#include "core/mesh_checks.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

#include "core/mesh_topology.h"

namespace chordfit {

namespace {

// After this many problems of one kind only a count of the rest is printed.
constexpr int kMaxReportedPerKind = 5;

class CappedReporter {
 public:
  CappedReporter(const std::string& file, Diagnostics& diagnostics, std::string summary)
      : file_(file), diagnostics_(diagnostics), summary_(std::move(summary)) {}
  ~CappedReporter() {
    if (count_ > kMaxReportedPerKind) {
      diagnostics_.error(file_, "",
                         std::to_string(count_ - kMaxReportedPerKind) + " more " + summary_);
    }
  }
  void report(const std::string& where, const std::string& what) {
    if (++count_ <= kMaxReportedPerKind) diagnostics_.error(file_, where, what);
  }
  int count() const { return count_; }

 private:
  const std::string& file_;
  Diagnostics& diagnostics_;
  std::string summary_;
  int count_ = 0;
};

using Edge = std::pair<int, int>;
Edge undirected(int a, int b) { return a < b ? Edge{a, b} : Edge{b, a}; }

std::map<Edge, int> edgeFaceCounts(const Eigen::MatrixXi& F) {
  std::map<Edge, int> counts;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) ++counts[undirected(F(f, k), F(f, (k + 1) % 3))];
  }
  return counts;
}

bool checkIndices(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const std::string& file,
                  Diagnostics& diagnostics) {
  CappedReporter out(file, diagnostics, "faces with out-of-range vertex indices");
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      if (F(f, k) < 0 || F(f, k) >= V.rows()) {
        out.report("face " + std::to_string(f), "vertex index " + std::to_string(F(f, k)) +
                                                    " out of range (mesh has " +
                                                    std::to_string(V.rows()) + " vertices)");
        break;
      }
    }
  }
  return out.count() == 0;
}

bool checkFinite(const Eigen::MatrixXd& V, const std::string& file, Diagnostics& diagnostics) {
  CappedReporter out(file, diagnostics, "vertices with non-finite coordinates");
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(V(v, k))) {
        out.report("vertex " + std::to_string(v), std::string("coordinate ") + "xyz"[k] + " is " +
                                                      (std::isnan(V(v, k)) ? "NaN" : "infinite"));
        break;
      }
    }
  }
  return out.count() == 0;
}

bool checkDegenerate(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const std::string& file,
                     Diagnostics& diagnostics) {
  // Zero area relative to the mesh size: |cross| below 1e-12 of the squared bounding-box
  // diagonal is round-off, not geometry.
  const double diagonal = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  const double tolerance = 1e-12 * diagonal * diagonal;
  CappedReporter out(file, diagnostics, "zero-area triangles");
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const double twice_area = (b - a).cross(c - a).norm();
    if (twice_area <= tolerance) {
      out.report("face " + std::to_string(f), "degenerate triangle (zero area)");
    }
  }
  return out.count() == 0;
}

bool checkManifoldEdges(const Eigen::MatrixXi& F, const std::string& file,
                        Diagnostics& diagnostics) {
  CappedReporter out(file, diagnostics, "non-manifold edges");
  for (const auto& [edge, count] : edgeFaceCounts(F)) {
    if (count > 2) {
      out.report("edge (" + std::to_string(edge.first) + ", " + std::to_string(edge.second) + ")",
                 "non-manifold edge shared by " + std::to_string(count) + " triangles");
    }
  }
  return out.count() == 0;
}

}  // namespace

bool checkMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const std::string& file,
               Diagnostics& diagnostics, bool check_areas) {
  if (V.rows() < 3 || F.rows() < 1) {
    diagnostics.error(file, "",
                      "mesh has " + std::to_string(V.rows()) + " vertices and " +
                          std::to_string(F.rows()) + " triangles; need a surface");
    return false;
  }
  const bool finite = checkFinite(V, file, diagnostics);
  // Geometry checks read V at face indices: only safe once the indices are known good.
  if (!checkIndices(V, F, file, diagnostics)) return false;
  const bool manifold = checkManifoldEdges(F, file, diagnostics);
  const bool nondegenerate = finite && (!check_areas || checkDegenerate(V, F, file, diagnostics));
  // A vertex in no triangle has no mass: the simulator holds it where it is, and the contact
  // treats it as a fixed, invisible obstacle for every triangle that comes near it (a stray
  // vertex under a clamped sheet stopped its bulge at 1.9 of 4.9 mm); the metrics would count
  // it as tissue.
  std::vector<bool> referenced(static_cast<std::size_t>(V.rows()), false);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) referenced[static_cast<std::size_t>(F(f, k))] = true;
  CappedReporter stray(file, diagnostics, "vertices in no triangle");
  for (Eigen::Index v = 0; v < V.rows(); ++v)
    if (!referenced[static_cast<std::size_t>(v)])
      stray.report("vertices[" + std::to_string(v) + "]",
                   "vertex in no triangle (remove it: it would act as a fixed obstacle)");
  return finite && manifold && nondegenerate && stray.count() == 0;
}

bool checkAnnulusRing(const Eigen::MatrixXi& F, int vertex_count, const Eigen::VectorXi& ring,
                      const std::string& file, const std::string& where, Diagnostics& diagnostics) {
  if (ring.size() < 3) {
    diagnostics.error(file, where,
                      "annulus ring needs at least 3 vertices, got " + std::to_string(ring.size()));
    return false;
  }
  bool ok = true;
  std::set<int> seen;
  for (Eigen::Index i = 0; i < ring.size(); ++i) {
    if (ring(i) < 0 || ring(i) >= vertex_count) {
      diagnostics.error(file, where + "[" + std::to_string(i) + "]",
                        "vertex index " + std::to_string(ring(i)) + " out of range (mesh has " +
                            std::to_string(vertex_count) + " vertices)");
      ok = false;
    } else if (!seen.insert(ring(i)).second) {
      diagnostics.error(
          file, where + "[" + std::to_string(i) + "]",
          "vertex " + std::to_string(ring(i)) + " appears twice; the ring must be a simple loop");
      ok = false;
    }
  }
  if (!ok) return false;
  const std::map<Edge, int> counts = edgeFaceCounts(F);
  CappedReporter out(file, diagnostics, "ring steps that are not boundary edges");
  for (Eigen::Index i = 0; i < ring.size(); ++i) {
    const int a = ring(i);
    const int b = ring((i + 1) % ring.size());
    const auto it = counts.find(undirected(a, b));
    const std::string step =
        where + "[" + std::to_string(i) + "]->[" + std::to_string((i + 1) % ring.size()) + "]";
    if (it == counts.end()) {
      out.report(step, "vertices " + std::to_string(a) + " and " + std::to_string(b) +
                           " are not joined by a mesh edge; the ring is not a closed loop");
    } else if (it->second != 1) {
      out.report(step, "edge (" + std::to_string(a) + ", " + std::to_string(b) +
                           ") is not on the mesh boundary");
    }
  }
  if (out.count() != 0) return false;
  // Every piece of the mesh hangs from the annulus: a piece without a ring vertex has nothing
  // holding it (a stray copy of the leaflets drifted to the step cap, exit 0).
  const Eigen::VectorXi piece = vertexComponents(F, vertex_count);
  std::vector<bool> anchored(vertex_count, false);  // per piece id
  for (Eigen::Index i = 0; i < ring.size(); ++i) anchored[piece(ring(i))] = true;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    if (anchored[piece(F(f, 0))]) continue;
    diagnostics.error(file, where,
                      "mesh triangle " + std::to_string(f) +
                          " belongs to a piece of the mesh that no ring vertex is on: every "
                          "piece must hang from the annulus (a stray copy or fragment?)");
    return false;
  }
  return true;
}

}  // namespace chordfit
