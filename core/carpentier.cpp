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
    const Eigen::Vector3d start = 0.5 * (point(i - 1) + point(i));
    const Eigen::Vector3d end = 0.5 * (point(j) + point(j + 1));
    double sweep = wrapPi(annulusAngle(frame, point(i)) - annulusAngle(frame, start));
    for (int k = i; k < j; ++k) {
      sweep += wrapPi(annulusAngle(frame, point(k + 1)) - annulusAngle(frame, point(k)));
    }
    sweep += wrapPi(annulusAngle(frame, end) - annulusAngle(frame, point(j)));
    LeafletArc arc{run_label, annulusAngle(frame, start), sweep};
    if (lateralCoordinate(frame, end) > lateralCoordinate(frame, start)) {
      arc.theta_start = annulusAngle(frame, end);
      arc.sweep = -sweep;
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
