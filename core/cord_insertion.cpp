#include "core/cord_insertion.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/xpbd_constraints.h"

namespace chordfit {
namespace {

using Vec3 = Eigen::Vector3d;

// The bump k(d) = (1 - d^2/r^2)^2 inside the radius, 0 outside.
double bump(double distance2, double radius2) {
  if (distance2 >= radius2) return 0.0;
  const double s = 1.0 - distance2 / radius2;
  return s * s;
}

// The point itself, its vertices and weights as given (the order of the sums in the cord
// projection, so a closure with point insertions is bit-identical to one without patches).
CordInsertionWeights pointInsertion(const std::vector<int>& vertices,
                                    const std::vector<double>& weights) {
  return {vertices, weights};
}

}  // namespace

CordInsertionWeights cordInsertionWeights(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                          const std::vector<int>& point_vertices,
                                          const std::vector<double>& point_weights,
                                          double radius_mm) {
  if (!(radius_mm > 0.0)) return pointInsertion(point_vertices, point_weights);
  Vec3 p0 = Vec3::Zero();
  for (std::size_t m = 0; m < point_vertices.size(); ++m)
    p0 += point_weights[m] * V.row(point_vertices[m]).transpose();
  const double radius2 = radius_mm * radius_mm;
  std::map<int, double> lumped;  // ordered: the same weights in the same order on every run
  double total = 0.0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = V.row(F(f, 0)).transpose(), b = V.row(F(f, 1)).transpose(),
               c = V.row(F(f, 2)).transpose();
    double ba, bb, bc;
    closestPointOnTriangle(p0, a, b, c, ba, bb, bc);
    if ((ba * a + bb * b + bc * c - p0).squaredNorm() >= radius2) continue;
    const double area = 0.5 * (b - a).cross(c - a).norm();
    if (!(area > 0.0)) continue;
    // Midpoint rule on the n^2 congruent sub-triangles of a regular split, each of area A/n^2,
    // sampled at its centroid; n makes the longest sub-edge at most r/4.
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const int n = std::clamp(static_cast<int>(std::ceil(4.0 * longest / radius_mm)), 1, 256);
    const double cell = area / (static_cast<double>(n) * n);
    double sums[3] = {0.0, 0.0, 0.0};
    for (int i = 0; i < n; ++i) {
      for (int j = 0; i + j < n; ++j) {
        // Upward sub-triangle (i, j), (i+1, j), (i, j+1) and, where it exists, the downward
        // one (i+1, j), (i+1, j+1), (i, j+1), in barycentric units of 1/n.
        for (int down = 0; down < 2; ++down) {
          if (down == 1 && i + j + 1 >= n) continue;
          const double u = (down ? i + 2.0 / 3.0 : i + 1.0 / 3.0) / n;
          const double v = (down ? j + 2.0 / 3.0 : j + 1.0 / 3.0) / n;
          const double w0 = 1.0 - u - v;
          const Vec3 y = w0 * a + u * b + v * c;
          const double k = bump((y - p0).squaredNorm(), radius2) * cell;
          sums[0] += k * w0;
          sums[1] += k * u;
          sums[2] += k * v;
        }
      }
    }
    for (int m = 0; m < 3; ++m) {
      if (sums[m] <= 0.0) continue;
      lumped[F(f, m)] += sums[m];
      total += sums[m];
    }
  }
  if (!(total > 0.0)) return pointInsertion(point_vertices, point_weights);
  CordInsertionWeights result;
  for (const auto& [vertex, weight] : lumped) {
    result.vertices.push_back(vertex);
    result.weights.push_back(weight / total);
  }
  return result;
}

CordInsertionWeights cordInsertionWeights(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                          int vertex, const std::optional<CordPoint>& point,
                                          double radius_mm) {
  if (!point) return cordInsertionWeights(V, F, std::vector<int>{vertex}, {1.0}, radius_mm);
  return cordInsertionWeights(V, F, {point->vertices.begin(), point->vertices.end()},
                              {point->weights(0), point->weights(1), point->weights(2)}, radius_mm);
}

std::vector<CordInsertionWeights> cordInsertions(const ValveMesh& mesh, const CordSet& set,
                                                 double radius_mm) {
  std::vector<CordInsertionWeights> insertions;
  insertions.reserve(set.cords.size());
  for (const Cord& cord : set.cords)
    insertions.push_back(cordInsertionWeights(mesh.V, mesh.F, cord.vertex, cord.point, radius_mm));
  return insertions;
}

Eigen::Vector3d insertionPosition(const CordInsertionWeights& insertion, const Eigen::MatrixXd& V) {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (std::size_t m = 0; m < insertion.vertices.size(); ++m)
    position += insertion.weights[m] * V.row(insertion.vertices[m]).transpose();
  return position;
}

Eigen::VectorXd closedSpans(const CordSet& set, const std::vector<CordInsertionWeights>& insertions,
                            const Eigen::MatrixXd& V_closed) {
  Eigen::VectorXd spans(static_cast<Eigen::Index>(set.cords.size()));
  for (std::size_t c = 0; c < set.cords.size(); ++c) {
    const PmTip& tip = set.tips.at(set.cords[c].tip);
    const Eigen::Vector3d end = tip.closed_position ? *tip.closed_position : tip.position;
    spans(static_cast<Eigen::Index>(c)) =
        (insertionPosition(insertions.at(c), V_closed) - end).norm();
  }
  return spans;
}

}  // namespace chordfit
