#include "core/carpentier.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

namespace chordfit {

namespace {

constexpr double kTwoPi = 6.283185307179586;

// Wraps an angle difference into (-pi, pi].
double wrapPi(double angle) {
  angle = std::fmod(angle + M_PI, kTwoPi);
  if (angle <= 0.0) angle += kTwoPi;
  return angle - M_PI;
}

double lateralCoordinate(const AnnulusFrame& frame, const Eigen::Vector3d& p) {
  return frame.l.dot(p - frame.plane.centre);
}

// In-plane coordinates (a, l) of p about the annulus centre.
Eigen::Vector2d inPlane(const AnnulusFrame& frame, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - frame.plane.centre;
  return {frame.a.dot(d), frame.l.dot(d)};
}

// The point of the polyline `run` where the angle swept from its start (`swept`, one value per
// point) first reaches `target`, linear between points; the last point if it never does.
Eigen::Vector3d ringPointAtSweep(const std::vector<Eigen::Vector3d>& run,
                                 const std::vector<double>& swept, double target) {
  for (std::size_t k = 1; k < run.size(); ++k) {
    const double lo = std::min(swept[k - 1], swept[k]), hi = std::max(swept[k - 1], swept[k]);
    if (target < lo || target > hi) continue;
    const double t = hi > lo ? (target - swept[k - 1]) / (swept[k] - swept[k - 1]) : 0.0;
    return (1.0 - t) * run[k - 1] + t * run[k];
  }
  return run.back();
}

// Position of p along an arc as a fraction of its sweep (0 at theta_start, 1 at the far end);
// outside the arc the fraction is < 0 or > 1, measured toward the nearer end.
double arcFraction(const LeafletArc& arc, double theta) {
  const double direction = arc.sweep >= 0.0 ? 1.0 : -1.0;
  double along = std::fmod(direction * (theta - arc.theta_start), kTwoPi);
  if (along < 0.0) along += kTwoPi;
  const double extent = std::abs(arc.sweep);
  if (along <= extent) return along / extent;
  const double past_end = along - extent;
  const double before_start = kTwoPi - along;
  return past_end < before_start ? 1.0 + past_end / extent : -before_start / extent;
}

}  // namespace

double annulusAngle(const AnnulusFrame& frame, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - frame.plane.centre;
  return std::atan2(frame.l.dot(d), frame.a.dot(d));
}

SegmentMap buildSegmentMap(const Eigen::MatrixXd& ring_positions, const ValveMesh& mesh,
                           const AnnulusFrame& frame) {
  SegmentMap map;
  map.frame = frame;
  map.leaflet_names = mesh.leaflet_names;
  const int n = static_cast<int>(mesh.annulus.size());
  if (n < 3) return map;
  auto label = [&](int i) { return mesh.leaflet(mesh.annulus(((i % n) + n) % n)); };
  auto point = [&](int i) -> Eigen::Vector3d {
    return ring_positions.row(((i % n) + n) % n).transpose();
  };

  // Start the walk just after a label change so that every run is seen whole.
  int first = -1;
  for (int i = 0; i < n; ++i) {
    if (label(i) != label(i - 1)) {
      first = i;
      break;
    }
  }
  if (first < 0) {  // a single leaflet all round: one arc covering the full circle
    map.arcs.push_back({label(0), annulusAngle(frame, point(0)), kTwoPi});
    return map;
  }

  int i = first;
  while (i < first + n) {
    const int run_label = label(i);
    int j = i;
    while (j + 1 < first + n && label(j + 1) == run_label) ++j;
    // Commissures: midpoints of the ring edges where the label changes.
    // The run from commissure to commissure and the angle swept up to each of its points.
    std::vector<Eigen::Vector3d> run{0.5 * (point(i - 1) + point(i))};
    for (int k = i; k <= j; ++k) run.push_back(point(k));
    run.push_back(0.5 * (point(j) + point(j + 1)));
    std::vector<double> swept{0.0};
    for (std::size_t k = 1; k < run.size(); ++k) {
      swept.push_back(swept.back() +
                      wrapPi(annulusAngle(frame, run[k]) - annulusAngle(frame, run[k - 1])));
    }
    const Eigen::Vector3d& start = run.front();
    const Eigen::Vector3d& end = run.back();
    const double sweep = swept.back();
    LeafletArc arc{run_label, annulusAngle(frame, start), sweep};
    arc.commissure_start = inPlane(frame, start);
    arc.commissure_end = inPlane(frame, end);
    for (int third = 0; third < 2; ++third) {
      arc.ring_third[third] =
          inPlane(frame, ringPointAtSweep(run, swept, sweep * (third + 1) / 3.0));
    }
    if (lateralCoordinate(frame, end) > lateralCoordinate(frame, start)) {
      arc.theta_start = annulusAngle(frame, end);
      arc.sweep = -sweep;
      std::swap(arc.commissure_start, arc.commissure_end);
      std::swap(arc.ring_third[0], arc.ring_third[1]);
    }
    map.arcs.push_back(arc);
    i = j + 1;
  }
  return map;
}

SegmentMap openStateSegmentMap(const ValveMesh& mesh) {
  Eigen::MatrixXd ring(mesh.annulus.size(), 3);
  for (Eigen::Index k = 0; k < mesh.annulus.size(); ++k) ring.row(k) = mesh.V.row(mesh.annulus(k));
  return buildSegmentMap(ring, mesh, openAnnulusFrame(mesh));
}

namespace {

// The arc of `leaflet` (or, when leaflet < 0, of any leaflet) nearest to angle theta, with the
// point's fraction along it and how far outside [0, 1] it lies, in radians (0 when inside).
struct ArcHit {
  const LeafletArc* arc = nullptr;
  double fraction = 0.0;
  double outside = std::numeric_limits<double>::infinity();
};

ArcHit nearestArc(const SegmentMap& map, double theta, int leaflet) {
  ArcHit hit;
  for (const LeafletArc& arc : map.arcs) {
    if (leaflet >= 0 && arc.leaflet != leaflet) continue;
    const double fraction = arcFraction(arc, theta);
    const double outside = std::max({0.0, -fraction, fraction - 1.0}) * std::abs(arc.sweep);
    if (outside < hit.outside) hit = {&arc, fraction, outside};
  }
  return hit;
}

// A labelled point lying more than this far outside its own leaflet's arc, but inside it when
// seen from the opposite side of the centre, has crossed the valve centre (closed leaflets
// overlap past the centre at the coaptation line) and is localised on its leaflet's side.
// Smaller excursions are commissural tissue just beyond a commissure and are clamped.
constexpr double kCrossedCentreRad = M_PI / 4.0;

}  // namespace

ArcPosition arcPositionOf(const SegmentMap& map, const Eigen::Vector3d& p, int leaflet) {
  const double theta = annulusAngle(map.frame, p);
  ArcHit hit = nearestArc(map, theta, leaflet);
  if (hit.arc == nullptr) return {};
  if (leaflet >= 0 && hit.outside > kCrossedCentreRad) {
    const ArcHit opposite = nearestArc(map, theta + M_PI, leaflet);
    if (opposite.outside == 0.0) hit = opposite;
  }
  return {hit.arc->leaflet, std::min(std::max(hit.fraction, 0.0), 1.0)};
}

int segmentOf(const SegmentMap& map, const Eigen::Vector3d& p, int leaflet) {
  const ArcPosition position = arcPositionOf(map, p, leaflet);
  if (position.leaflet < 0) return -1;
  const int index = std::min(2, static_cast<int>(position.fraction * 3.0));
  return position.leaflet * 3 + index;
}

int closedSegmentOf(const SegmentMap& map, const Eigen::Vector3d& p, int leaflet) {
  const ArcPosition position = arcPositionOf(map, p, leaflet);
  if (position.leaflet < 0) return -1;
  const LeafletArc* arc = nullptr;
  for (const LeafletArc& a : map.arcs)
    if (a.leaflet == position.leaflet) arc = &a;
  const Eigen::Vector2d chord = arc->commissure_end - arc->commissure_start;
  if (chord.norm() < 1e-9) return segmentOf(map, p, leaflet);
  const Eigen::Vector2d q = inPlane(map.frame, p);
  int index = 0;
  for (int k = 0; k < 2; ++k) {
    // Boundary k: ring point at (k + 1)/3 of the arc -> point at (k + 1)/3 of the chord. The
    // start commissure lies on the side of segment 0; past the boundary means the other side.
    const Eigen::Vector2d& from = arc->ring_third[k];
    Eigen::Vector2d direction = arc->commissure_start + chord * ((k + 1) / 3.0) - from;
    if (direction.norm() < 1e-9) direction = Eigen::Vector2d(-chord.y(), chord.x());
    const double start_side = cross2d(direction, arc->commissure_start - from);
    if (cross2d(direction, q - from) * start_side > 0.0) break;
    index = k + 1;
  }
  return position.leaflet * 3 + index;
}

std::string segmentName(const std::vector<std::string>& leaflet_names, int segment_id) {
  if (segment_id < 0) return "?";
  const int leaflet = segment_id / 3;
  std::string prefix =
      leaflet < static_cast<int>(leaflet_names.size()) && !leaflet_names[leaflet].empty()
          ? std::string(1, static_cast<char>(
                               std::toupper(static_cast<unsigned char>(leaflet_names[leaflet][0]))))
          : "L" + std::to_string(leaflet);
  return prefix + std::to_string(segment_id % 3 + 1);
}

std::string segmentName(const SegmentMap& map, int segment_id) {
  return segmentName(map.leaflet_names, segment_id);
}

}  // namespace chordfit
