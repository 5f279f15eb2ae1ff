#include "core/cord_attachments.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/annulus_plane.h"
#include "core/carpentier.h"
#include "core/heuristic.h"
#include "core/xpbd_constraints.h"

namespace chordfit {

namespace {

// Samples per leaflet when measuring the free-edge and belly-line lengths.
constexpr int kLengthSamples = 256;

// One meridian column of the parametric mesh (parametric_valve.h: column k is the vertex
// range annulus[k] .. free_edge[k], in order of arc length from the annulus).
struct Column {
  double fraction = 0.0;  // along its leaflet's arc, 0 at the anterolateral commissure
  int first = 0, last = 0;
  std::vector<double> arc;  // cumulative length from the annulus vertex
  double height() const { return arc.back(); }
};

// Columns of one leaflet, by increasing fraction.
struct LeafletColumns {
  std::vector<Column> columns;
};

LeafletColumns leafletColumns(const ParametricValve& valve, int leaflet) {
  const ValveMesh& mesh = valve.valve_case.mesh;
  const Eigen::Index count = mesh.annulus.size();
  if (valve.free_edge.size() != count) {
    throw std::invalid_argument("parametric valve: free edge and annulus differ in size");
  }
  const SegmentMap map = openStateSegmentMap(mesh);
  LeafletColumns result;
  if (std::none_of(map.arcs.begin(), map.arcs.end(),
                   [&](const LeafletArc& a) { return a.leaflet == leaflet; })) {
    return result;
  }
  for (Eigen::Index k = 0; k < count; ++k) {
    if (mesh.leaflet(mesh.annulus(k)) != leaflet) continue;
    Column column;
    column.first = mesh.annulus(k);
    column.last = valve.free_edge(k);
    // The valve's own fraction when it has one: the mesh ring's commissures lie up to half a
    // ring edge off the curve's, which would move every point attachment with the mesh.
    column.fraction =
        valve.column_fraction.size() == count
            ? valve.column_fraction(k)
            : arcPositionOf(map, mesh.V.row(column.first).transpose(), leaflet).fraction;
    column.arc.push_back(0.0);
    for (int v = column.first + 1; v <= column.last; ++v) {
      column.arc.push_back(column.arc.back() + (mesh.V.row(v) - mesh.V.row(v - 1)).norm());
    }
    result.columns.push_back(std::move(column));
  }
  std::sort(result.columns.begin(), result.columns.end(),
            [](const Column& a, const Column& b) { return a.fraction < b.fraction; });
  return result;
}

// Point of a column at `depth` from its free edge (clamped to the annulus).
Eigen::Vector3d columnPoint(const Eigen::MatrixXd& V, const Column& column, double depth) {
  if (column.arc.size() < 2) return V.row(column.first).transpose();
  const double s = std::max(0.0, column.height() - std::max(0.0, depth));
  const auto it = std::upper_bound(column.arc.begin(), column.arc.end(), s);
  const int i = std::clamp(static_cast<int>(it - column.arc.begin()) - 1, 0,
                           static_cast<int>(column.arc.size()) - 2);
  const double span = column.arc[i + 1] - column.arc[i];
  const double t = span > 0.0 ? std::clamp((s - column.arc[i]) / span, 0.0, 1.0) : 0.0;
  return (1.0 - t) * V.row(column.first + i).transpose() +
         t * V.row(column.first + i + 1).transpose();
}

// Bracketing columns and weight of the second: value = (1 - t) f(j) + t f(j + 1).
void bracket(const LeafletColumns& leaflet, double fraction, int& j, double& t) {
  const auto& c = leaflet.columns;
  if (c.size() == 1 || fraction <= c.front().fraction) {
    j = 0;
    t = 0.0;
    return;
  }
  if (fraction >= c.back().fraction) {
    j = static_cast<int>(c.size()) - 2;
    t = 1.0;
    return;
  }
  j = 0;
  while (c[j + 1].fraction < fraction) ++j;
  t = (fraction - c[j].fraction) / (c[j + 1].fraction - c[j].fraction);
}

const LeafletColumns& requireColumns(const LeafletColumns& columns, int leaflet) {
  if (columns.columns.empty()) {
    throw std::invalid_argument("cord attachment: leaflet " + std::to_string(leaflet) +
                                " has no annulus column on this valve");
  }
  return columns;
}

Eigen::Vector3d pointOn(const Eigen::MatrixXd& V, const LeafletColumns& leaflet, double fraction,
                        double depth) {
  int j = 0;
  double t = 0.0;
  bracket(leaflet, fraction, j, t);
  const Eigen::Vector3d a = columnPoint(V, leaflet.columns[j], depth);
  if (t == 0.0) return a;
  return (1.0 - t) * a + t * columnPoint(V, leaflet.columns[j + 1], depth);
}

double heightOn(const LeafletColumns& leaflet, double fraction) {
  int j = 0;
  double t = 0.0;
  bracket(leaflet, fraction, j, t);
  const double a = leaflet.columns[j].height();
  return t == 0.0 ? a : (1.0 - t) * a + t * leaflet.columns[j + 1].height();
}

// Length of the curve fraction -> point(fraction, depth) over [0, 1].
double lineLength(const Eigen::MatrixXd& V, const LeafletColumns& leaflet, double depth) {
  double length = 0.0;
  Eigen::Vector3d previous = pointOn(V, leaflet, 0.0, depth);
  for (int i = 1; i <= kLengthSamples; ++i) {
    const Eigen::Vector3d p = pointOn(V, leaflet, static_cast<double>(i) / kLengthSamples, depth);
    length += (p - previous).norm();
    previous = p;
  }
  return length;
}

}  // namespace

int AnatomicalAttachment::segment() const {
  const int index = std::clamp(static_cast<int>(std::floor(3.0 * fraction)), 0, 2);
  return 3 * leaflet + index;
}

Eigen::Vector3d attachmentPoint(const ParametricValve& valve, int leaflet, double fraction,
                                double depth_mm) {
  const LeafletColumns columns = leafletColumns(valve, leaflet);
  return pointOn(valve.valve_case.mesh.V, requireColumns(columns, leaflet), fraction, depth_mm);
}

double leafletHeightAt(const ParametricValve& valve, int leaflet, double fraction) {
  const LeafletColumns columns = leafletColumns(valve, leaflet);
  return heightOn(requireColumns(columns, leaflet), fraction);
}

std::vector<AnatomicalAttachment> layoutAttachments(const ParametricValve& valve,
                                                    const AttachmentLayoutOptions& options) {
  const ValveMesh& mesh = valve.valve_case.mesh;
  const int leaflets = static_cast<int>(mesh.leaflet_names.size());
  std::vector<LeafletColumns> columns;
  for (int leaflet = 0; leaflet < leaflets; ++leaflet) {
    columns.push_back(leafletColumns(valve, leaflet));
  }
  auto make = [](int leaflet, double fraction, double depth, CordKind kind) {
    AnatomicalAttachment a;
    a.leaflet = leaflet;
    a.fraction = fraction;
    a.depth_mm = depth;
    a.kind = kind;
    a.tip = fraction <= 0.5 ? 0 : 1;
    return a;
  };

  std::vector<AnatomicalAttachment> out;
  for (int leaflet = 0; leaflet < leaflets; ++leaflet) {
    if (columns[leaflet].columns.empty()) continue;
    const double length = lineLength(mesh.V, columns[leaflet], 0.0);
    const int count =
        std::max(1, spacedCordCount(length, options.primary_spacing_mm, "primary cord spacing"));
    for (int i = 0; i < count; ++i) {
      const double fraction = (i + 0.5) / count;
      if (heightOn(columns[leaflet], fraction) < options.min_annulus_distance_mm) continue;
      out.push_back(make(leaflet, fraction, 0.0, CordKind::kPrimary));
    }
  }
  for (int leaflet = 0; leaflet < leaflets; ++leaflet) {
    if (columns[leaflet].columns.empty()) continue;
    const double depth = options.secondary_depth_mm;
    const double length = lineLength(mesh.V, columns[leaflet], depth);
    const int count =
        spacedCordCount(length, options.secondary_spacing_mm, "secondary cord spacing");
    for (int i = 0; i < count; ++i) {
      const double fraction = (i + 0.5) / count;
      if (heightOn(columns[leaflet], fraction) < depth + options.min_annulus_distance_mm) continue;
      out.push_back(make(leaflet, fraction, depth, CordKind::kSecondary));
    }
  }
  return out;
}

namespace {

// Where each attachment lies on the valve's own surface (attachmentPoint, for many at once).
// Throws std::invalid_argument for a leaflet the valve does not have.
std::vector<Eigen::Vector3d> surfacePoints(const ParametricValve& valve,
                                           const std::vector<AnatomicalAttachment>& attachments) {
  const ValveMesh& mesh = valve.valve_case.mesh;
  const int leaflets = static_cast<int>(mesh.leaflet_names.size());
  std::vector<LeafletColumns> columns;
  for (int leaflet = 0; leaflet < leaflets; ++leaflet) {
    columns.push_back(leafletColumns(valve, leaflet));
  }
  std::vector<Eigen::Vector3d> points;
  for (const AnatomicalAttachment& a : attachments) {
    if (a.leaflet < 0 || a.leaflet >= leaflets) {
      throw std::invalid_argument("cord attachment: leaflet " + std::to_string(a.leaflet) +
                                  " does not exist");
    }
    points.push_back(
        pointOn(mesh.V, requireColumns(columns[a.leaflet], a.leaflet), a.fraction, a.depth_mm));
  }
  return points;
}

}  // namespace

std::vector<int> mapAttachments(const ParametricValve& valve,
                                const std::vector<AnatomicalAttachment>& attachments) {
  const ValveMesh& mesh = valve.valve_case.mesh;
  const std::vector<Eigen::Vector3d> targets = surfacePoints(valve, attachments);
  std::vector<bool> taken(mesh.V.rows(), false);
  for (Eigen::Index i = 0; i < mesh.annulus.size(); ++i) taken[mesh.annulus(i)] = true;

  std::vector<int> vertices;
  for (std::size_t i = 0; i < attachments.size(); ++i) {
    const AnatomicalAttachment& a = attachments[i];
    const Eigen::Vector3d& p = targets[i];
    int best = -1;
    double best_distance = std::numeric_limits<double>::infinity();
    for (Eigen::Index v = 0; v < mesh.V.rows(); ++v) {
      if (taken[v] || mesh.leaflet(v) != a.leaflet) continue;
      const double d = (mesh.V.row(v).transpose() - p).squaredNorm();
      if (d < best_distance) {
        best_distance = d;
        best = static_cast<int>(v);
      }
    }
    if (best < 0) {
      throw std::invalid_argument("cord attachment: leaflet " + std::to_string(a.leaflet) +
                                  " has fewer free vertices than cords; use a finer mesh");
    }
    taken[best] = true;
    vertices.push_back(best);
  }
  return vertices;
}

std::vector<CordPoint> pointAttachments(const ParametricValve& valve,
                                        const std::vector<AnatomicalAttachment>& attachments) {
  const ValveMesh& mesh = valve.valve_case.mesh;
  const std::vector<Eigen::Vector3d> targets = surfacePoints(valve, attachments);
  // Triangles touching the annulus ring are left out: a weight on a Dirichlet vertex does
  // not move, so a point near it could reach its rest length only by throwing the free
  // vertices far (dx_m = b_m w_m n dlambda / sum(b^2 w), xpbd_constraints.h).
  std::vector<bool> on_ring(mesh.V.rows(), false);
  for (Eigen::Index i = 0; i < mesh.annulus.size(); ++i) on_ring[mesh.annulus(i)] = true;
  std::vector<CordPoint> points;
  for (std::size_t i = 0; i < attachments.size(); ++i) {
    const AnatomicalAttachment& a = attachments[i];
    const Eigen::Vector3d& p = targets[i];
    CordPoint best;
    double best_distance = std::numeric_limits<double>::infinity();
    for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
      const Eigen::Vector3i t = mesh.F.row(f).transpose();
      if (mesh.leaflet(t(0)) != a.leaflet || mesh.leaflet(t(1)) != a.leaflet ||
          mesh.leaflet(t(2)) != a.leaflet || on_ring[t(0)] || on_ring[t(1)] || on_ring[t(2)]) {
        continue;
      }
      double b[3];
      const Eigen::Vector3d x0 = mesh.V.row(t(0)).transpose(), x1 = mesh.V.row(t(1)).transpose(),
                            x2 = mesh.V.row(t(2)).transpose();
      closestPointOnTriangle(p, x0, x1, x2, b[0], b[1], b[2]);
      const double d = (b[0] * x0 + b[1] * x1 + b[2] * x2 - p).squaredNorm();
      if (d < best_distance) {
        best_distance = d;
        best.vertices = {t(0), t(1), t(2)};
        // Clamp the closest-point barycentrics' rounding so the weights are >= 0 and sum to 1.
        Eigen::Vector3d w(std::max(b[0], 0.0), std::max(b[1], 0.0), std::max(b[2], 0.0));
        best.weights = w / w.sum();
      }
    }
    if (!std::isfinite(best_distance)) {
      throw std::invalid_argument("cord attachment: leaflet " + std::to_string(a.leaflet) +
                                  " has no triangle");
    }
    points.push_back(best);
  }
  return points;
}

int largestWeightVertex(const CordPoint& point) {
  Eigen::Index m = 0;
  point.weights.maxCoeff(&m);
  return point.vertices[static_cast<std::size_t>(m)];
}

CordSet attachmentCordSet(const std::vector<AnatomicalAttachment>& attachments,
                          const std::vector<CordPoint>& points) {
  std::vector<int> vertices;
  for (const CordPoint& p : points) vertices.push_back(largestWeightVertex(p));
  CordSet set = attachmentCordSet(attachments, vertices);
  for (std::size_t i = 0; i < set.cords.size(); ++i) set.cords[i].point = points.at(i);
  return set;
}

CordSet attachmentCordSet(const std::vector<AnatomicalAttachment>& attachments,
                          const std::vector<int>& vertices) {
  CordSet set;
  set.tips.resize(2);
  set.tips[0].name = "anterolateral";
  set.tips[1].name = "posteromedial";
  for (std::size_t i = 0; i < attachments.size(); ++i) {
    Cord cord;
    cord.tip = attachments[i].tip;
    cord.vertex = vertices.at(i);
    cord.kind = attachments[i].kind;
    set.cords.push_back(cord);
  }
  return set;
}

}  // namespace chordfit
