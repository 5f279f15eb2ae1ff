#include "core/case_extent.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <Eigen/Geometry>

#include "core/annulus_plane.h"

namespace chordfit {
namespace {

std::string millimetres(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g mm", value);
  return text;
}

// "; farthest from the median of the vertices: vertex K at (x, y, z), D away": the vertex to
// look at when one outlier (a stray point at 1e10 mm) rather than the units makes the span.
std::string farthestVertexNote(const Eigen::MatrixXd& V) {
  Eigen::RowVector3d median;
  for (int k = 0; k < 3; ++k) {
    std::vector<double> column(V.col(k).data(), V.col(k).data() + V.rows());
    std::nth_element(column.begin(), column.begin() + column.size() / 2, column.end());
    median(k) = column[column.size() / 2];
  }
  Eigen::Index farthest = 0;
  (V.rowwise() - median).rowwise().norm().maxCoeff(&farthest);
  const Eigen::RowVector3d p = V.row(farthest);
  char text[160];
  std::snprintf(text, sizeof text,
                "; farthest from the median of the vertices: vertex %ld at (%.3g, %.3g, %.3g), "
                "%s away",
                static_cast<long>(farthest), p.x(), p.y(), p.z(),
                millimetres((p - median).stableNorm()).c_str());
  return text;
}

}  // namespace

double boundingDiagonal(const Eigen::MatrixXd& V) {
  if (V.rows() == 0) return 0.0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff())
      .stableNorm();  // a stray 1e200 stays finite
}

bool checkValveSpan(const Eigen::MatrixXd& V, const std::string& file, Diagnostics& diagnostics) {
  const double span = boundingDiagonal(V);
  if (span >= kMinValveSpanMm && span <= kMaxValveSpanMm) return true;
  diagnostics.error(file, "vertices",
                    "the mesh spans " + millimetres(span) + " (bounding-box diagonal); a mitral " +
                        "valve spans 30-60 mm and coordinates must be in millimetres (accepted: " +
                        millimetres(kMinValveSpanMm) + " to " + millimetres(kMaxValveSpanMm) + ")" +
                        (span > kMaxValveSpanMm ? farthestVertexNote(V) : ""));
  return false;
}

double valveReachMm(const Eigen::MatrixXd& mesh_V) {
  return std::max(50.0, boundingDiagonal(mesh_V));
}

namespace {

// The region a case's other points must lie in: within `reach` of the mesh's bounding box.
struct ValveReach {
  Eigen::RowVector3d lo, hi;
  double reach;
  explicit ValveReach(const Eigen::MatrixXd& mesh_V)
      : lo(mesh_V.colwise().minCoeff()),
        hi(mesh_V.colwise().maxCoeff()),
        reach(valveReachMm(mesh_V)) {}

  // True when p lies within reach; otherwise reports it as (file, where) and returns false.
  // NaN lies nowhere.
  bool check(const Eigen::RowVector3d& p, const std::string& file, const std::string& where,
             Diagnostics& diagnostics, bool report = true) const {
    // stableNorm: a coordinate near 1e308 would overflow norm() to inf.
    const double distance = (lo - p).cwiseMax(p - hi).cwiseMax(0.0).stableNorm();  // from the box
    if (distance <= reach) return true;
    if (report) {
      char position[96];
      std::snprintf(position, sizeof position, "(%.4g, %.4g, %.4g)", p(0), p(1), p(2));
      diagnostics.error(file, where,
                        std::string(position) + " lies " + millimetres(distance) +
                            " from the valve mesh (every point must be within " +
                            millimetres(reach) + " of its bounding box)");
    }
    return false;
  }
};

}  // namespace

namespace {

// How point k is named in messages: where the file has it (Curve::point_wheres, e.g. "line 4"
// of a .csv) or, without that, `list_where`[k].
std::string pointWhere(const std::vector<std::string>& point_wheres, Eigen::Index k,
                       const std::string& list_where) {
  return static_cast<std::size_t>(k) < point_wheres.size()
             ? point_wheres[static_cast<std::size_t>(k)]
             : list_where + "[" + std::to_string(k) + "]";
}

// Errors (file, pointWhere(point_wheres, k, list_where)) for the points out of reach, the
// first few of them, and a count of the others at (file, summary_where).
bool checkEachPointNearValve(const Eigen::MatrixXd& mesh_V, const Eigen::MatrixXd& points,
                             const std::string& file, const std::vector<std::string>& point_wheres,
                             const std::string& list_where, const std::string& summary_where,
                             Diagnostics& diagnostics) {
  if (mesh_V.rows() == 0) return true;
  const ValveReach valve(mesh_V);
  constexpr int kReported = 3;
  int far = 0;
  for (Eigen::Index k = 0; k < points.rows(); ++k) {
    if (!valve.check(points.row(k), file, pointWhere(point_wheres, k, list_where), diagnostics,
                     far < kReported))
      ++far;
  }
  if (far > kReported) {
    diagnostics.error(file, summary_where,
                      std::to_string(far - kReported) + " more point(s) as far from the valve");
  }
  return far == 0;
}

}  // namespace

bool checkPointsNearValve(const Eigen::MatrixXd& mesh_V, const Eigen::MatrixXd& points,
                          const std::string& file, const std::string& where,
                          Diagnostics& diagnostics) {
  return checkEachPointNearValve(mesh_V, points, file, {}, where, where, diagnostics);
}

bool checkCurveNearValve(const Eigen::MatrixXd& mesh_V, const Curve& curve, const std::string& file,
                         Diagnostics& diagnostics) {
  return checkEachPointNearValve(mesh_V, curve.points, file, curve.point_wheres, "points", "",
                                 diagnostics);
}

namespace {

// Newell's normal of a closed polygon (twice its vector area) and its perimeter.
Eigen::Vector3d polygonNormal(const Eigen::MatrixXd& P) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k < P.rows(); ++k) {
    const Eigen::Vector3d a = P.row(k).transpose(), b = P.row((k + 1) % P.rows()).transpose();
    n += a.cross(b);
  }
  return n;
}

double perimeter(const Eigen::MatrixXd& P) {
  double length = 0.0;
  for (Eigen::Index k = 0; k < P.rows(); ++k)
    length += (P.row((k + 1) % P.rows()) - P.row(k)).norm();
  return length;
}

// Whether segments ab and cd of the plane cross at a point inside both (orientation tests;
// sides that only touch or overlap in line do not count).
bool segmentsCross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                   const Eigen::Vector2d& d) {
  auto side = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r) {
    const double cross = cross2d(q - p, r - p);
    return (cross > 0.0) - (cross < 0.0);
  };
  return side(a, b, c) * side(a, b, d) < 0 && side(c, d, a) * side(c, d, b) < 0;
}

// The first pair of sides (k, j), k < j, of polygon P seen along `normal` that cross each
// other, or {-1, -1}. Sides k and k+1 share a point and are not compared.
std::pair<Eigen::Index, Eigen::Index> firstCrossingSides(const Eigen::MatrixXd& P,
                                                         const Eigen::Vector3d& normal) {
  const Eigen::Vector3d n = normal.normalized();
  const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
  const Eigen::Index count = P.rows();
  std::vector<Eigen::Vector2d> q(count);
  for (Eigen::Index k = 0; k < count; ++k)
    q[k] = Eigen::Vector2d(P.row(k).dot(u.transpose()), P.row(k).dot(v.transpose()));
  for (Eigen::Index k = 0; k < count; ++k)
    for (Eigen::Index j = k + 2; j < count; ++j) {
      if (k == 0 && j == count - 1) continue;  // neighbours across the start
      if (segmentsCross(q[k], q[k + 1], q[j], q[(j + 1) % count])) return {k, j};
    }
  return {-1, -1};
}

}  // namespace

bool checkClosedAnnulus(const Eigen::MatrixXd& open_ring, const Eigen::MatrixXd& closed,
                        const std::string& file, Diagnostics& diagnostics,
                        const std::vector<std::string>& point_wheres) {
  const auto where = [&](Eigen::Index k) { return pointWhere(point_wheres, k, "points"); };
  if (open_ring.rows() < 3 || closed.rows() != open_ring.rows()) return true;  // checked elsewhere
  const double open_length = perimeter(open_ring), closed_length = perimeter(closed);
  // 0.5: the parametric valve's closed annulus drawn in to 0.35 of its size made the closure
  // diverge, to 0.4 it closed; an adult annulus shortens by about a quarter at most.
  if (!(closed_length >= 0.5 * open_length && closed_length <= 4.0 * open_length)) {
    diagnostics.error(file, "points",
                      "the closed annulus is " + millimetres(closed_length) +
                          " around against the ring's " + millimetres(open_length) +
                          " (accepted: 0.5 to 4 times)");
    return false;
  }
  if (!(polygonNormal(open_ring).dot(polygonNormal(closed)) > 0.0)) {
    diagnostics.error(file, "points",
                      "the closed annulus runs the other way round than the annulus ring: its "
                      "points must follow the ring's vertex order");
    return false;
  }
  // No side squeezed to nothing: a repeated (or nearly repeated) point tears the mesh where the
  // ring is pulled onto it (the closure diverged). Measured against the ring's mean side, as
  // a segmented ring's sides may differ several times over and a closed curve resampled by
  // arc length need not follow them.
  const Eigen::Index n = open_ring.rows();
  const double mean_open_side = open_length / static_cast<double>(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double closed_side = (closed.row((k + 1) % n) - closed.row(k)).norm();
    if (!(closed_side >= 0.1 * mean_open_side)) {
      diagnostics.error(file, where(k),
                        "the side to " + where((k + 1) % n) + " is " + millimetres(closed_side) +
                            " long, under a tenth of the ring's mean " +
                            millimetres(mean_open_side) + ": a repeated point?");
      return false;
    }
  }
  // No side crossing another, seen along the ring's normal: two points swapped (or a point
  // out of place) passed the checks above and made the closure diverge (exit 3) at step 62.
  if (const auto [k, j] = firstCrossingSides(closed, polygonNormal(open_ring)); k >= 0) {
    const auto side = [&](Eigen::Index s) { return where(s) + " to " + where((s + 1) % n); };
    diagnostics.error(file, where(k + 1),
                      "the closed annulus crosses itself: its side " + side(k) +
                          " crosses the side " + side(j) +
                          " (seen along the annulus ring's normal): points swapped or out of "
                          "order?");
    return false;
  }
  // The same start: the points, each polygon about its own centre (the annulus may move as a
  // whole between the phases), lie nearest the ring with no cyclic shift. A list shifted by a
  // few places, or turned by half (x and y negated), passed the checks above and then pulled
  // every ring vertex across the orifice.
  const Eigen::RowVector3d open_centre = open_ring.colwise().mean();
  const Eigen::RowVector3d closed_centre = closed.colwise().mean();
  auto shiftCost = [&](Eigen::Index shift) {
    double cost = 0.0;
    for (Eigen::Index k = 0; k < n; ++k)
      cost += ((closed.row((k + shift) % n) - closed_centre) - (open_ring.row(k) - open_centre))
                  .squaredNorm();
    return cost;
  };
  const double unshifted = shiftCost(0);
  Eigen::Index best = 0;
  double best_cost = unshifted;
  for (Eigen::Index shift = 1; shift < n; ++shift) {
    if (const double cost = shiftCost(shift); cost < best_cost) best = shift, best_cost = cost;
  }
  // Only a shift by an eighth of the ring or more: a few places are a small rotation of the
  // annulus between the phases, or a resampled curve starting half a spacing off (import-mesh
  // anchors the commissures at the curve's nearest points).
  const Eigen::Index shift_size = std::min(best, n - best);
  if (best != 0 && 8 * shift_size >= n && best_cost < 0.5 * unshifted) {
    diagnostics.error(file, "points",
                      "the closed annulus fits the ring best shifted by " + std::to_string(best) +
                          " of " + std::to_string(n) + " places (its point " +
                          std::to_string(best) +
                          " lies where ring vertex 0 is): the points must follow the ring's "
                          "vertex order from the same start" +
                          (2 * best == n || 2 * best == n + 1 || 2 * best == n - 1
                               ? " (half a turn: a file in RAS read as LPS, or the other way?)"
                               : ""));
    return false;
  }
  return true;
}

bool checkTipsNearValve(const Eigen::MatrixXd& mesh_V, const std::vector<PmTip>& tips,
                        const std::string& file, Diagnostics& diagnostics) {
  if (mesh_V.rows() == 0) return true;
  const ValveReach valve(mesh_V);
  bool ok = true;
  for (std::size_t t = 0; t < tips.size(); ++t) {
    const std::string where = "tips[" + std::to_string(t) + "]";
    ok &= valve.check(tips[t].position.transpose(), file, where + ".position", diagnostics);
    if (tips[t].closed_position)
      ok &= valve.check(tips[t].closed_position->transpose(), file, where + ".closed_position",
                        diagnostics);
  }
  if (const auto [earlier, later] = tipsTooClose(tips); later >= 0) {
    diagnostics.error(file, "tips[" + std::to_string(later) + "].position",
                      "less than 1 mm from tips[" + std::to_string(earlier) +
                          "].position: two PM tips in one place");
    ok = false;
  }
  return ok;
}

std::pair<int, int> tipsTooClose(const std::vector<PmTip>& tips) {
  for (std::size_t t = 0; t < tips.size(); ++t)
    for (std::size_t earlier = 0; earlier < t; ++earlier)
      if ((tips[t].position - tips[earlier].position).norm() < kMinPmTipSeparationMm)
        return {static_cast<int>(earlier), static_cast<int>(t)};
  return {-1, -1};
}

bool checkTipsBelowAnnulus(const ValveMesh& mesh, const std::vector<PmTip>& tips,
                           const std::string& file, Diagnostics& diagnostics) {
  if (mesh.annulus.size() < 3) return true;  // the ring's own checks report it
  for (Eigen::Index i = 0; i < mesh.annulus.size(); ++i)
    if (mesh.annulus(i) < 0 || mesh.annulus(i) >= mesh.V.rows()) return true;
  const Plane plane = openAnnulusFrame(mesh).plane;
  bool ok = true;
  for (std::size_t t = 0; t < tips.size(); ++t) {
    const double height = plane.signedDistance(tips[t].position);
    if (height < 0.0) continue;
    char what[240];
    std::snprintf(what, sizeof what,
                  "%.1f mm on the atrial side of the open annulus plane: PM tips lie below it, "
                  "in the ventricle the leaflets hang into (a tip in another frame, or a sign "
                  "slip?)",
                  height);
    diagnostics.error(file, "tips[" + std::to_string(t) + "].position", what);
    ok = false;
  }
  return ok;
}

bool checkTipPlacement(const ValveMesh& mesh, const std::vector<PmTip>& tips,
                       const std::string& file, Diagnostics& diagnostics) {
  const bool near = checkTipsNearValve(mesh.V, tips, file, diagnostics);
  return checkTipsBelowAnnulus(mesh, tips, file, diagnostics) && near;
}

}  // namespace chordfit
