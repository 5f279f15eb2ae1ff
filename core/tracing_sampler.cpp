#include "core/tracing_sampler.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <map>
#include <stdexcept>
#include <utility>

#include <Eigen/Geometry>

namespace chordfit {

namespace {

// One image plane, as written by different tools: normals within 1e-3 rad (0.06 degrees) and
// the origins within 0.01 mm across. Over a 50 mm valve such planes part by at most 0.05 mm,
// far below the tracings' noise (0.3 mm in the cohort) and voxel size; normals rounded to 5 or
// 6 decimals by another tool split one plane in two at the 1e-6 used before (a second section
// panel, the mesh cut twice by the prolapse check and the section residuals).
constexpr double kSamePlaneNormalRad = 1e-3;
constexpr double kSamePlaneOffsetMm = 0.01;

// Unit normals of either sign: a reader's file may orient one plane's polylines both ways.
bool samePlane(const Eigen::Vector3d& origin_a, const Eigen::Vector3d& normal_a,
               const Eigen::Vector3d& origin_b, const Eigen::Vector3d& normal_b) {
  return normal_a.cross(normal_b).norm() < kSamePlaneNormalRad &&
         std::abs(normal_a.dot(origin_b - origin_a)) < kSamePlaneOffsetMm;
}

constexpr double kPi = 3.14159265358979323846;
// Consecutive section points closer than this are one point (a vertex lying on the plane
// produces zero-length segments).
constexpr double kDuplicateMm = 1e-9;

using EdgeKey = std::pair<int, int>;

EdgeKey edgeKey(int a, int b) { return a < b ? EdgeKey{a, b} : EdgeKey{b, a}; }

// One cut triangle: its face and the crossing points (ids) at its two cut edges.
struct Segment {
  int face = 0;
  std::array<int, 2> point{0, 0};
};

// Drops consecutive duplicates; returns #P by 3.
Eigen::MatrixXd withoutDuplicates(const std::vector<Eigen::Vector3d>& points) {
  std::vector<Eigen::Vector3d> kept;
  for (const Eigen::Vector3d& p : points) {
    if (kept.empty() || (p - kept.back()).norm() > kDuplicateMm) kept.push_back(p);
  }
  Eigen::MatrixXd P(kept.size(), 3);
  for (std::size_t i = 0; i < kept.size(); ++i) P.row(i) = kept[i].transpose();
  return P;
}

}  // namespace

std::vector<ImagePlane> longAxisPlanes(const AnnulusFrame& frame, int count) {
  if (count < 1) throw std::invalid_argument("tracing planes: need at least 1 plane");
  std::vector<ImagePlane> planes;
  const Eigen::Vector3d n = frame.plane.normal.normalized();
  for (int i = 0; i < count; ++i) {
    ImagePlane plane;
    plane.angle = i * kPi / count;
    plane.origin = frame.plane.centre;
    plane.u = (std::cos(plane.angle) * frame.a + std::sin(plane.angle) * frame.l).normalized();
    plane.w = n;
    plane.normal = n.cross(plane.u).normalized();
    planes.push_back(plane);
  }
  return planes;
}

bool tracedOnPlane(const Tracing& t, const ImagePlane& plane) {
  return samePlane(plane.origin, plane.normal, t.plane_origin, t.plane_normal);
}

std::vector<ImagePlane> tracingPlanes(const std::vector<Tracing>& tracings,
                                      const AnnulusFrame& frame) {
  const Eigen::Vector3d up = frame.plane.normal.normalized();
  std::vector<ImagePlane> planes;
  for (const Tracing& t : tracings) {
    const Eigen::Vector3d& normal = t.plane_normal;
    const bool known = std::any_of(planes.begin(), planes.end(),
                                   [&](const ImagePlane& p) { return tracedOnPlane(t, p); });
    if (known) continue;
    ImagePlane plane;
    plane.origin = t.plane_origin;
    plane.normal = normal;
    Eigen::Vector3d w = up - up.dot(normal) * normal;
    // A short-axis plane (parallel to the annulus plane) has no "up": use the AP axis.
    if (w.norm() < 1e-6) w = frame.a - frame.a.dot(normal) * normal;
    plane.w = w.normalized();
    plane.u = normal.cross(plane.w).normalized();
    double angle = std::atan2(plane.u.dot(frame.l), plane.u.dot(frame.a));
    if (angle < 0.0) angle += kPi;
    if (angle >= kPi - 1e-9) angle -= kPi;
    plane.angle = std::max(0.0, angle);
    planes.push_back(plane);
  }
  return planes;
}

Eigen::VectorXi faceLeaflets(const Eigen::MatrixXi& F, const Eigen::VectorXi& vertex_leaflet) {
  Eigen::VectorXi labels(F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const int a = vertex_leaflet(F(f, 0)), b = vertex_leaflet(F(f, 1)), c = vertex_leaflet(F(f, 2));
    if (a == b || a == c) {
      labels(f) = a;
    } else if (b == c) {
      labels(f) = b;
    } else {
      labels(f) = std::min({a, b, c});
    }
  }
  return labels;
}

std::vector<SectionPolyline> planeSection(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                          const Eigen::VectorXi& face_leaflet,
                                          const Eigen::Vector3d& origin,
                                          const Eigen::Vector3d& normal) {
  const Eigen::Vector3d n = normal.normalized();
  const Eigen::VectorXd d = (V.rowwise() - origin.transpose()) * n;
  auto positive = [&](int v) { return d(v) >= 0.0; };

  std::map<EdgeKey, int> point_of_edge;
  std::vector<Eigen::Vector3d> points;
  std::vector<Segment> segments;
  auto crossing = [&](int a, int b) {
    const EdgeKey key = edgeKey(a, b);
    const auto it = point_of_edge.find(key);
    if (it != point_of_edge.end()) return it->second;
    const double t = d(key.first) / (d(key.first) - d(key.second));
    points.push_back(V.row(key.first).transpose() +
                     t * (V.row(key.second) - V.row(key.first)).transpose());
    const int id = static_cast<int>(points.size()) - 1;
    point_of_edge.emplace(key, id);
    return id;
  };
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    Segment segment;
    segment.face = static_cast<int>(f);
    int cuts = 0;
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      if (positive(a) != positive(b)) segment.point[cuts++] = crossing(a, b);
    }
    if (cuts == 2) segments.push_back(segment);
  }

  // Point -> the (at most two) segments through it.
  std::vector<std::vector<int>> at_point(points.size());
  for (std::size_t s = 0; s < segments.size(); ++s) {
    for (int p : segments[s].point) at_point[p].push_back(static_cast<int>(s));
  }

  std::vector<bool> used(segments.size(), false);
  std::vector<SectionPolyline> out;
  for (std::size_t first = 0; first < segments.size(); ++first) {
    if (used[first]) continue;
    used[first] = true;
    // Chain: points p_0..p_m and faces f_0..f_{m-1}, face i between p_i and p_{i+1}.
    std::deque<int> chain_points{segments[first].point[0], segments[first].point[1]};
    std::deque<int> chain_faces{segments[first].face};
    for (int direction = 0; direction < 2; ++direction) {
      while (true) {
        const int end = direction == 0 ? chain_points.back() : chain_points.front();
        int next = -1;
        for (int s : at_point[end]) {
          if (!used[s]) next = s;
        }
        if (next < 0) break;
        used[next] = true;
        const Segment& seg = segments[next];
        const int other = seg.point[0] == end ? seg.point[1] : seg.point[0];
        if (direction == 0) {
          chain_points.push_back(other);
          chain_faces.push_back(seg.face);
        } else {
          chain_points.push_front(other);
          chain_faces.push_front(seg.face);
        }
      }
    }
    // Split into runs of one leaflet.
    std::size_t run_start = 0;
    for (std::size_t i = 1; i <= chain_faces.size(); ++i) {
      if (i < chain_faces.size() &&
          face_leaflet(chain_faces[i]) == face_leaflet(chain_faces[run_start])) {
        continue;
      }
      std::vector<Eigen::Vector3d> run;
      for (std::size_t j = run_start; j <= i; ++j) run.push_back(points[chain_points[j]]);
      SectionPolyline polyline;
      polyline.points = withoutDuplicates(run);
      polyline.leaflet = face_leaflet(chain_faces[run_start]);
      if (polyline.points.rows() >= 2) out.push_back(std::move(polyline));
      run_start = i;
    }
  }
  return out;
}

Eigen::MatrixXd resamplePolyline(const Eigen::MatrixXd& P, double spacing) {
  if (!(spacing > 0.0)) throw std::invalid_argument("resamplePolyline: spacing must be > 0");
  if (P.rows() < 2) return P;
  std::vector<double> arc(P.rows(), 0.0);
  for (Eigen::Index i = 1; i < P.rows(); ++i)
    arc[i] = arc[i - 1] + (P.row(i) - P.row(i - 1)).norm();
  const double length = arc.back();
  std::vector<Eigen::Vector3d> out;
  std::size_t j = 0;
  for (int k = 0; k * spacing < length - 1e-9 * spacing; ++k) {
    const double s = k * spacing;
    while (j + 2 < arc.size() && arc[j + 1] < s) ++j;
    const double span = arc[j + 1] - arc[j];
    const double t = span > 0.0 ? std::clamp((s - arc[j]) / span, 0.0, 1.0) : 0.0;
    out.push_back(((1.0 - t) * P.row(j) + t * P.row(j + 1)).transpose());
  }
  out.push_back(P.row(P.rows() - 1).transpose());
  Eigen::MatrixXd R(out.size(), 3);
  for (std::size_t i = 0; i < out.size(); ++i) R.row(i) = out[i].transpose();
  return R;
}

std::vector<Tracing> sampleTracings(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                    const Eigen::VectorXi& vertex_leaflet,
                                    const AnnulusFrame& frame, const TracingSamplerOptions& options,
                                    SeededRandom& random) {
  if (!(options.spacing_mm > 0.0)) throw std::invalid_argument("tracings: spacing must be > 0");
  if (!(options.noise_mm >= 0.0)) throw std::invalid_argument("tracings: noise must be >= 0");
  if (!(options.dropout_fraction >= 0.0 && options.dropout_fraction < 1.0)) {
    throw std::invalid_argument("tracings: dropout fraction must be in [0, 1)");
  }
  const Eigen::VectorXi face_leaflet = faceLeaflets(F, vertex_leaflet);
  const std::vector<ImagePlane> planes = longAxisPlanes(frame, options.planes);

  // Resampled polylines of every plane, with their global arc-length offsets.
  struct Piece {
    int plane = 0;
    int leaflet = -1;
    Eigen::MatrixXd points;
    std::vector<double> position;  // global arc length of each point
  };
  std::vector<Piece> pieces;
  double total = 0.0;
  for (std::size_t i = 0; i < planes.size(); ++i) {
    for (const SectionPolyline& section :
         planeSection(V, F, face_leaflet, planes[i].origin, planes[i].normal)) {
      Piece piece;
      piece.plane = static_cast<int>(i);
      piece.leaflet = section.leaflet;
      piece.points = resamplePolyline(section.points, options.spacing_mm);
      double s = total;
      for (Eigen::Index r = 0; r < piece.points.rows(); ++r) {
        if (r > 0) s += (piece.points.row(r) - piece.points.row(r - 1)).norm();
        piece.position.push_back(s);
      }
      total = s;
      pieces.push_back(std::move(piece));
    }
  }

  // Dropout gaps: G gaps of length g = D / G; sorted u_i ~ U[0, total - D], gap i starts at
  // u_i + i g (uniform non-overlapping placement).
  const int gap_count = options.dropout_pieces > 0
                            ? options.dropout_pieces
                            : std::max(1, static_cast<int>(std::lround(options.planes / 2.0)));
  const double dropped = options.dropout_fraction * total;
  const double gap = dropped / gap_count;
  std::vector<double> starts;
  if (dropped > 0.0) {
    for (int g = 0; g < gap_count; ++g) starts.push_back(random.uniform(0.0, total - dropped));
    std::sort(starts.begin(), starts.end());
    for (int g = 0; g < gap_count; ++g) starts[g] += g * gap;
  }
  auto in_gap = [&](double s) {
    for (double start : starts) {
      if (s >= start && s < start + gap) return true;
    }
    return false;
  };

  std::vector<Tracing> tracings;
  for (const Piece& piece : pieces) {
    const ImagePlane& plane = planes[piece.plane];
    std::vector<Eigen::Vector3d> run;
    auto flush = [&]() {
      if (run.size() >= 2) {
        Tracing t;
        t.points.resize(static_cast<Eigen::Index>(run.size()), 3);
        for (std::size_t r = 0; r < run.size(); ++r) {
          const Eigen::Vector3d p = run[r] + options.noise_mm * (random.gaussian() * plane.u +
                                                                 random.gaussian() * plane.w);
          t.points.row(static_cast<Eigen::Index>(r)) = p.transpose();
        }
        t.plane_origin = plane.origin;
        t.plane_normal = plane.normal;
        t.leaflet = piece.leaflet;
        tracings.push_back(std::move(t));
      }
      run.clear();
    };
    for (Eigen::Index r = 0; r < piece.points.rows(); ++r) {
      if (in_gap(piece.position[r])) {
        flush();
      } else {
        run.push_back(piece.points.row(r).transpose());
      }
    }
    flush();
  }
  return tracings;
}

}  // namespace chordfit
