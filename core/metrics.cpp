#include "core/metrics.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <set>

#include "core/cgal_backend.h"
#include "core/joined.h"
#include "core/simulator.h"
#include "core/tracing_sampler.h"

namespace chordfit {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kTwoPi = 6.283185307179586;
}  // namespace

Eigen::VectorXd pointToSurfaceDistances(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                        const Eigen::MatrixXd& points) {
  Eigen::VectorXd d(points.rows());
  if (points.rows() == 0) return d;
  const SurfaceDistance surface(V, F);
  for (Eigen::Index i = 0; i < points.rows(); ++i) d(i) = surface.distance(points.row(i));
  return d;
}

Eigen::VectorXd pointToOwnLeafletDistances(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                           const Eigen::VectorXi& face_leaflet,
                                           const Eigen::MatrixXd& points,
                                           const Eigen::VectorXi& point_leaflet) {
  Eigen::VectorXd d(points.rows());
  if (points.rows() == 0) return d;
  // One AABB tree per leaflet label some point asks for; the whole mesh only when needed.
  std::map<int, std::vector<Eigen::Index>> faces_of;
  for (Eigen::Index f = 0; f < F.rows(); ++f) faces_of[face_leaflet(f)].push_back(f);
  std::map<int, std::unique_ptr<SurfaceDistance>> leaflet_surface;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const int label = point_leaflet(i);
    const auto faces = faces_of.find(label);
    if (label < 0 || faces == faces_of.end() || leaflet_surface.count(label) > 0) continue;
    Eigen::MatrixXi sub(static_cast<Eigen::Index>(faces->second.size()), 3);
    for (std::size_t k = 0; k < faces->second.size(); ++k) sub.row(k) = F.row(faces->second[k]);
    leaflet_surface[label] = std::make_unique<SurfaceDistance>(V, sub);
  }
  std::unique_ptr<SurfaceDistance> whole;  // built only if some point has no own leaflet
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const auto own = leaflet_surface.find(point_leaflet(i));
    if (own != leaflet_surface.end()) {
      d(i) = own->second->distance(points.row(i));
      continue;
    }
    if (!whole) whole = std::make_unique<SurfaceDistance>(V, F);
    d(i) = whole->distance(points.row(i));
  }
  return d;
}

double median(std::vector<double> values) {
  if (values.empty()) return kNaN;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

DeviationStats summarizeDeviation(const Eigen::VectorXd& distances) {
  DeviationStats s;
  s.count = static_cast<int>(distances.size());
  if (s.count == 0) {
    s.min = s.median = s.max = s.mean = s.sd = kNaN;
    return s;
  }
  std::vector<double> sorted(distances.data(), distances.data() + distances.size());
  std::sort(sorted.begin(), sorted.end());
  s.min = sorted.front();
  s.max = sorted.back();
  s.median = median(sorted);
  s.mean = distances.mean();
  s.sd = s.count > 1 ? std::sqrt((distances.array() - s.mean).square().sum() / (s.count - 1)) : 0.0;
  return s;
}

double surfaceArea(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  double twice = 0.0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    twice += (b - a).cross(c - a).norm();
  }
  return 0.5 * twice;
}

Eigen::MatrixXd stackTracingPoints(const std::vector<Tracing>& tracings,
                                   Eigen::VectorXi* leaflets) {
  Eigen::Index total = 0;
  for (const Tracing& t : tracings) total += t.points.rows();
  Eigen::MatrixXd points(total, 3);
  if (leaflets) leaflets->resize(total);
  Eigen::Index row = 0;
  for (const Tracing& t : tracings) {
    points.middleRows(row, t.points.rows()) = t.points;
    if (leaflets) leaflets->segment(row, t.points.rows()).setConstant(t.leaflet);
    row += t.points.rows();
  }
  return points;
}

namespace {

struct RingPoint {
  double theta;   // angle around the centre in the frame
  double radius;  // in-plane distance from the centre
  double height;  // signed distance to the plane
};

std::vector<RingPoint> ringPolar(const AnnulusFrame& frame, const Eigen::MatrixXd& ring) {
  std::vector<RingPoint> polar;
  for (Eigen::Index i = 0; i < ring.rows(); ++i) {
    const Eigen::Vector3d q = ring.row(i).transpose() - frame.plane.centre;
    const double u = frame.a.dot(q), v = frame.l.dot(q);
    polar.push_back({std::atan2(v, u), std::hypot(u, v), frame.plane.normal.dot(q)});
  }
  return polar;
}

// The annulus (radius, height) where the half-plane at angle theta cuts the ring: linear
// interpolation on the ring edge whose angular span contains theta.
std::pair<double, double> ringAt(const std::vector<RingPoint>& polar, double theta) {
  const std::size_t n = polar.size();
  double best_gap = std::numeric_limits<double>::infinity();
  std::pair<double, double> nearest{polar[0].radius, polar[0].height};
  for (std::size_t i = 0; i < n; ++i) {
    const RingPoint& p = polar[i];
    const RingPoint& q = polar[(i + 1) % n];
    const double span = std::remainder(q.theta - p.theta, kTwoPi);
    const double along = std::remainder(theta - p.theta, kTwoPi);
    if (span != 0.0 && along / span >= 0.0 && along / span <= 1.0) {
      const double t = along / span;
      return {p.radius + t * (q.radius - p.radius), p.height + t * (q.height - p.height)};
    }
    const double gap = std::abs(along);
    if (gap < best_gap) {
      best_gap = gap;
      nearest = {p.radius, p.height};
    }
  }
  return nearest;
}

}  // namespace

Eigen::VectorXd heightAboveAnnulus(const AnnulusFrame& frame, const Eigen::MatrixXd& ring,
                                   const Eigen::MatrixXd& points) {
  const std::vector<RingPoint> polar = ringPolar(frame, ring);
  Eigen::VectorXd heights(points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d q = points.row(i).transpose() - frame.plane.centre;
    const double u = frame.a.dot(q), v = frame.l.dot(q);
    const double r = std::hypot(u, v);
    const double theta = std::atan2(v, u);
    const auto [rho_near, z_near] = ringAt(polar, theta);
    const auto [rho_far, z_far] = ringAt(polar, theta + M_PI);
    // Hinge line from (-rho_far, z_far) to (rho_near, z_near) in the long-axis plane.
    const double t = std::clamp((r + rho_far) / (rho_near + rho_far), 0.0, 1.0);
    heights(i) = frame.plane.normal.dot(q) - (z_far + t * (z_near - z_far));
  }
  return heights;
}

ClosedAnnulus closedAnnulus(const ValveCase& valve_case) {
  ClosedAnnulus closed;
  // No closed annulus (a library caller's case; the case files require one): the annulus
  // stays at its open position, as in the closure model.
  if (valve_case.annulus_closed.rows() > 0) {
    closed.ring = valve_case.annulus_closed;
  } else {
    closed.ring.resize(valve_case.mesh.annulus.size(), 3);
    for (Eigen::Index k = 0; k < valve_case.mesh.annulus.size(); ++k)
      closed.ring.row(k) = valve_case.mesh.V.row(valve_case.mesh.annulus(k));
  }
  closed.frame =
      annulusFrameFromRing(closed.ring, valve_case.mesh, openAnnulusFrame(valve_case.mesh));
  closed.segments = buildSegmentMap(closed.ring, valve_case.mesh, closed.frame);
  return closed;
}

ProlapseResult prolapseOfPoints(const ClosedAnnulus& annulus, const Eigen::MatrixXd& points,
                                const Eigen::VectorXi& segment_ids,
                                const ProlapseOptions& options) {
  ProlapseResult result;
  result.heights = heightAboveAnnulus(annulus.frame, annulus.ring, points);
  result.max_height_mm = points.rows() > 0 ? result.heights.maxCoeff() : kNaN;
  std::map<int, int> above;       // segment id -> points above threshold
  std::map<int, double> highest;  // segment id -> highest point
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const int segment = segment_ids(i);
    if (segment < 0) continue;
    const auto [it, first] = highest.emplace(segment, result.heights(i));
    if (!first) it->second = std::max(it->second, result.heights(i));
    if (result.heights(i) > options.threshold_mm) ++above[segment];
  }
  for (const auto& [segment, height] : highest) {
    result.segment_max_height_mm[segmentName(annulus.segments, segment)] = height;
  }
  std::set<std::string> names;
  for (const auto& [segment, count] : above) {
    if (count >= options.min_points) {
      names.insert(segmentName(annulus.segments, segment));
    }
  }
  result.segments.assign(names.begin(), names.end());
  return result;
}

ProlapseResult prolapseOfLabelledPoints(const ClosedAnnulus& annulus, const Eigen::MatrixXd& points,
                                        const Eigen::VectorXi& leaflets,
                                        const ProlapseOptions& options) {
  Eigen::VectorXi segment_ids(points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    segment_ids(i) = closedSegmentOf(annulus.segments, points.row(i).transpose(), leaflets(i));
  }
  return prolapseOfPoints(annulus, points, segment_ids, options);
}

Eigen::VectorXi openStateSegments(const ValveMesh& mesh) {
  const SegmentMap open_map = openStateSegmentMap(mesh);
  Eigen::VectorXi ids(mesh.V.rows());
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v) {
    ids(v) = segmentOf(open_map, mesh.V.row(v).transpose(), mesh.leaflet(v));
  }
  return ids;
}

namespace {

ProlapseResult prolapseOfMesh(const ValveCase& valve_case, const ClosedAnnulus& annulus,
                              const Eigen::MatrixXd& closed_V, const ProlapseOptions& options) {
  const ValveMesh& mesh = valve_case.mesh;
  std::vector<bool> on_ring(mesh.V.rows(), false);
  for (Eigen::Index i = 0; i < mesh.annulus.size(); ++i) on_ring[mesh.annulus(i)] = true;
  const Eigen::VectorXi open_segments = openStateSegments(mesh);
  std::vector<int> rows;
  for (Eigen::Index v = 0; v < closed_V.rows(); ++v) {
    if (!on_ring[v]) rows.push_back(static_cast<int>(v));
  }
  Eigen::MatrixXd points(rows.size(), 3);
  Eigen::VectorXi segment_ids(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    points.row(i) = closed_V.row(rows[i]);
    segment_ids(i) = open_segments(rows[i]);
  }
  return prolapseOfPoints(annulus, points, segment_ids, options);
}

ProlapseResult prolapseOfTracings(const ValveCase& valve_case, const ClosedAnnulus& annulus,
                                  const ProlapseOptions& options) {
  Eigen::VectorXi leaflets;
  const Eigen::MatrixXd points = stackTracingPoints(valve_case.tracings, &leaflets);
  return prolapseOfLabelledPoints(annulus, points, leaflets, options);
}

}  // namespace

ProlapseResult prolapseOfMesh(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                              const ProlapseOptions& options) {
  return prolapseOfMesh(valve_case, closedAnnulus(valve_case), closed_V, options);
}

ProlapseResult prolapseOfTracings(const ValveCase& valve_case, const ProlapseOptions& options) {
  return prolapseOfTracings(valve_case, closedAnnulus(valve_case), options);
}

ProlapseResult prolapseOfSections(const ValveCase& valve_case, const ClosedAnnulus& annulus,
                                  const Eigen::MatrixXd& closed_V, double spacing_mm,
                                  const ProlapseOptions& options) {
  const Eigen::VectorXi face_leaflet = faceLeaflets(valve_case.mesh.F, valve_case.mesh.leaflet);
  // The sections as tracings (points resampled like the sampler's, leaflet of the cut).
  std::vector<Tracing> sections;
  for (const ImagePlane& plane : tracingPlanes(valve_case.tracings, annulus.frame)) {
    for (const SectionPolyline& section :
         planeSection(closed_V, valve_case.mesh.F, face_leaflet, plane.origin, plane.normal)) {
      Tracing t;
      t.points = resamplePolyline(section.points, spacing_mm);
      t.leaflet = section.leaflet;
      sections.push_back(std::move(t));
    }
  }
  Eigen::VectorXi labels;
  const Eigen::MatrixXd stacked = stackTracingPoints(sections, &labels);
  return prolapseOfLabelledPoints(annulus, stacked, labels, options);
}

ValveMetrics computeMetrics(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V) {
  ValveMetrics m;
  const Eigen::MatrixXd points = stackTracingPoints(valve_case.tracings);
  m.has_tracings = points.rows() > 0;
  m.tracing_distances = pointToSurfaceDistances(closed_V, valve_case.mesh.F, points);
  m.deviation = summarizeDeviation(m.tracing_distances);
  m.area_mm2 = surfaceArea(closed_V, valve_case.mesh.F);
  const ClosedAnnulus annulus = closedAnnulus(valve_case);
  m.mesh_prolapse = prolapseOfMesh(valve_case, annulus, closed_V, ProlapseOptions{});
  const Eigen::MatrixXd ring = closed_V(valve_case.mesh.annulus, Eigen::all);
  // The leaflets as tissue: the mid-surface grown by half the contact thickness of the case's
  // settings (orifice_coverage.h). The commands refuse a bad block when they load the case
  // (caseSettingsOrReport); a caller that did not check gets the default thickness for it.
  Diagnostics problems;
  const SimulationSettings settings = settingsFromJson(valve_case.simulation_json, problems);
  const double half_thickness =
      0.5 * contactThicknessMm(problems.ok() ? settings : SimulationSettings{});
  m.orifice =
      orificeCoverage(ring, closed_V, valve_case.mesh.F, annulus.frame, 0.25, half_thickness);
  m.self_intersections = countSelfIntersections(closed_V, valve_case.mesh.F);
  if (m.has_tracings) {
    m.tracing_prolapse = prolapseOfTracings(valve_case, annulus, ProlapseOptions{2.0, 2});
    m.section_prolapse = prolapseOfSections(valve_case, annulus, closed_V);
    m.prolapse_reconstructed = m.section_prolapse.segments == m.tracing_prolapse.segments;
    m.tissue_prolapse_reconstructed = m.mesh_prolapse.segments == m.tracing_prolapse.segments;
  }
  return m;
}

std::vector<std::string> prolapseMissing(const ProlapseResult& tracings,
                                         const ProlapseResult& sections) {
  std::vector<std::string> missing;
  for (const std::string& segment : tracings.segments)
    if (std::find(sections.segments.begin(), sections.segments.end(), segment) ==
        sections.segments.end())
      missing.push_back(segment);
  return missing;
}

std::vector<std::string> prolapseMissingInClosure(const ValveCase& valve_case,
                                                  const Eigen::MatrixXd& closed_V) {
  if (valve_case.tracings.empty()) return {};
  // The same criteria as computeMetrics' Table 1 verdict.
  const ClosedAnnulus annulus = closedAnnulus(valve_case);
  return prolapseMissing(prolapseOfTracings(valve_case, annulus, ProlapseOptions{2.0, 2}),
                         prolapseOfSections(valve_case, annulus, closed_V));
}

std::string table1Header(const std::string& first_column) {
  return "| " + first_column +
         " | Area (mm²) | MinD (mm) | MedD (mm) | MaxD (mm) | AvgD (mm) | Prolapse "
         "Recon. |\n|---|---:|---:|---:|---:|---:|---|\n";
}

std::string joinSegments(const std::vector<std::string>& segments) {
  return segments.empty() ? "none" : joined(segments, ", ");
}

namespace {

// "Yes (P2)": a bare Yes on a normal valve read as "it prolapses".
std::string reconstructedCell(const ValveMetrics& m) {
  if (m.prolapse_reconstructed) return "Yes (" + joinSegments(m.section_prolapse.segments) + ")";
  return "No (mesh " + joinSegments(m.section_prolapse.segments) + "; tracings " +
         joinSegments(m.tracing_prolapse.segments) + ")";
}

// A '|' in a label would split its Markdown cell.
std::string markdownCell(const std::string& text) {
  std::string cell;
  for (char ch : text) cell += ch == '|' ? std::string("\\|") : std::string(1, ch);
  return cell;
}

}  // namespace

std::string table1Row(const std::string& label_text, const ValveMetrics& m) {
  const std::string label = markdownCell(label_text);
  // The numbers only through snprintf: a label or segment list has no length limit.
  char numbers[160];
  if (m.has_tracings) {
    std::snprintf(numbers, sizeof numbers, "%.0f | %.2f | %.2f | %.2f | %.2f ± %.2f", m.area_mm2,
                  m.deviation.min, m.deviation.median, m.deviation.max, m.deviation.mean,
                  m.deviation.sd);
    return "| " + label + " | " + numbers + " | " + reconstructedCell(m) + " |\n";
  }
  std::snprintf(numbers, sizeof numbers, "%.0f", m.area_mm2);
  return "| " + label + " | " + numbers + " | – | – | – | – | – (no tracings) |\n";
}

}  // namespace chordfit
