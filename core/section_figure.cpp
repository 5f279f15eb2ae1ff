#include "core/section_figure.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/Geometry>

#include "core/metrics.h"

namespace chordfit {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Okabe & Ito colours, as enface.svg: anterior blue, posterior green (red is enface's open
// orifice); then for a third leaflet and more.
const char* const kLeafletColours[] = {"#0072b2", "#009e73", "#d55e00", "#8e44ad", "#b7950b"};
// Tracing points are hollow rings (SvgSeries::Kind::kRings) with a near-black rim: unlike a
// dot, a ring stays distinct from a line of any colour under it, compare's black one included.
constexpr const char* kTracingColour = "#111111";
constexpr double kTracingRadius = 1.8;  // px, to the middle of the rim
constexpr const char* kClosedAnnulusColour = "#e67e22";
constexpr const char* kOpenAnnulusColour = "#f5cba7";
// The prolapse threshold is dotted and thin: the seed closure of fit's figure is a dashed grey
// line, and the two must not be taken for each other where they cross.
constexpr const char* kThresholdColour = "#666666";
constexpr double kThresholdWidth = 1.2;  // px; the seed closure is 1.4

// The hinge line of heightAboveAnnulus raised by `threshold`: in a long-axis plane the height
// of a point is its w minus the straight line through the two closed ring crossings (sorted
// by u). Empty unless the ring crosses the plane exactly twice.
Eigen::MatrixXd thresholdLine(const Eigen::MatrixXd& hinges, double threshold) {
  if (hinges.rows() != 2) return {};
  const int left = hinges(0, 0) <= hinges(1, 0) ? 0 : 1;
  Eigen::MatrixXd line(2, 2);
  line.row(0) = hinges.row(left);
  line.row(1) = hinges.row(1 - left);
  line.col(1).array() += threshold;
  return line;
}

}  // namespace

Eigen::MatrixXd projectToPlane(const ImagePlane& plane, const Eigen::MatrixXd& P) {
  Eigen::MatrixXd Q(P.rows(), 2);
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const Eigen::Vector3d d = P.row(i).transpose() - plane.origin;
    Q(i, 0) = plane.u.dot(d);
    Q(i, 1) = plane.w.dot(d);
  }
  return Q;
}

Eigen::MatrixXd ringCrossings(const ImagePlane& plane, const Eigen::MatrixXd& ring) {
  std::vector<Eigen::Vector3d> hits;
  const Eigen::Index n = ring.rows();
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d p = ring.row(i).transpose(), q = ring.row((i + 1) % n).transpose();
    const double dp = plane.normal.dot(p - plane.origin), dq = plane.normal.dot(q - plane.origin);
    if ((dp >= 0.0) == (dq >= 0.0)) continue;
    hits.push_back(p + dp / (dp - dq) * (q - p));
  }
  Eigen::MatrixXd P(hits.size(), 3);
  for (std::size_t i = 0; i < hits.size(); ++i) P.row(i) = hits[i].transpose();
  return projectToPlane(plane, P);
}

std::string sectionFigureSvg(const ValveMesh& mesh, const Eigen::MatrixXd& closed_ring,
                             const std::vector<Tracing>& tracings,
                             const std::vector<ImagePlane>& planes,
                             const std::vector<SectionLayer>& layers,
                             const SectionFigureOptions& options) {
  const Eigen::VectorXi face_leaflet = faceLeaflets(mesh.F, mesh.leaflet);
  const int leaflets = mesh.leaflet.size() > 0 ? mesh.leaflet.maxCoeff() + 1 : 0;
  Eigen::MatrixXd open_ring(mesh.annulus.size(), 3);
  for (Eigen::Index i = 0; i < mesh.annulus.size(); ++i)
    open_ring.row(i) = mesh.V.row(mesh.annulus(i));

  std::vector<SvgPanel> panels;
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const ImagePlane& plane = planes[i];
    SvgPanel panel;
    char title[96];
    std::snprintf(title, sizeof title, "plane %zu: %.0f deg from the AP axis%s", i,
                  plane.angle * 180.0 / kPi,
                  std::abs(plane.angle) < 1e-6 ? " (anteroposterior)" : "");
    panel.title = title;

    for (const SectionLayer& layer : layers) {
      // One series per leaflet (colour by leaflet) or a single series.
      const bool by_leaflet = layer.colour.empty();
      std::vector<SvgSeries> series(by_leaflet ? std::max(leaflets, 1) : 1);
      for (std::size_t k = 0; k < series.size(); ++k) {
        series[k] = {SvgSeries::Kind::kLine,
                     {},
                     layer.colour,
                     layer.width,
                     layer.dashed ? SvgStroke::kDashed : SvgStroke::kSolid,
                     layer.label};
        if (!by_leaflet) continue;
        series[k].colour = kLeafletColours[k % std::size(kLeafletColours)];
        const std::string name =
            k < mesh.leaflet_names.size() ? mesh.leaflet_names[k] : "leaflet " + std::to_string(k);
        series[k].label = layer.label + ", " + name;
      }
      for (const SectionPolyline& p :
           planeSection(layer.V, mesh.F, face_leaflet, plane.origin, plane.normal)) {
        const std::size_t k =
            by_leaflet && p.leaflet >= 0 ? static_cast<std::size_t>(p.leaflet) % series.size() : 0;
        series[k].parts.push_back(projectToPlane(plane, p.points));
      }
      for (SvgSeries& s : series) panel.series.push_back(std::move(s));
    }

    const Eigen::MatrixXd hinges = ringCrossings(plane, closed_ring);
    if (options.open_annulus) {
      panel.series.push_back({SvgSeries::Kind::kSquares,
                              {ringCrossings(plane, open_ring)},
                              kOpenAnnulusColour,
                              3.0,
                              SvgStroke::kSolid,
                              "open annulus"});
    }
    panel.series.push_back({SvgSeries::Kind::kSquares,
                            {hinges},
                            kClosedAnnulusColour,
                            3.0,
                            SvgStroke::kSolid,
                            "closed annulus"});
    const Eigen::MatrixXd threshold = thresholdLine(hinges, options.threshold_mm);
    if (options.prolapse_threshold && threshold.rows() == 2) {
      char label[96];
      std::snprintf(label, sizeof label, "prolapse: hinges + %.0f mm", options.threshold_mm);
      panel.series.push_back({SvgSeries::Kind::kLine,
                              {threshold},
                              kThresholdColour,
                              kThresholdWidth,
                              SvgStroke::kDotted,
                              label});
    }
    SvgSeries points{SvgSeries::Kind::kRings, {}, kTracingColour, kTracingRadius, SvgStroke::kSolid,
                     options.tracing_label};
    for (const Tracing& t : tracings) {
      if (tracedOnPlane(t, plane)) points.parts.push_back(projectToPlane(plane, t.points));
    }
    panel.series.push_back(std::move(points));
    panels.push_back(std::move(panel));
  }
  SvgFigureOptions figure;
  figure.title = options.title;
  // u's direction (tracingPlanes: the plane's angle turns it from a toward l, the
  // anterolateral side), so that a reader can tell which end of a section is anterior.
  figure.x_label = "u (mm): +u anterior at 0 deg, turned toward AL";
  // Along n_AP from the image plane's origin, which is the annulus centre only for planes
  // placed about it (make-case's): a tracing file may put its origin anywhere in the plane.
  figure.y_label = "height along the annulus normal, atrium up (mm)";
  figure.columns = std::max(1, std::min<int>(3, static_cast<int>(planes.size())));
  return crossSectionsSvg(panels, figure);
}

std::string caseSectionFigureSvg(const ValveCase& valve_case,
                                 const std::vector<SectionLayer>& layers,
                                 const SectionFigureOptions& options) {
  if (valve_case.tracings.empty()) return "";
  const ClosedAnnulus closed = closedAnnulus(valve_case);
  // A tracing's normal may have either sign, and u = normal x w with it: turn each plane so
  // that +u is the direction at its angle from the anterior axis (as longAxisPlanes makes
  // them), the orientation the figure's axis label states.
  std::vector<ImagePlane> planes = tracingPlanes(valve_case.tracings, closed.frame);
  for (ImagePlane& plane : planes) {
    const Eigen::Vector3d at_angle =
        std::cos(plane.angle) * closed.frame.a + std::sin(plane.angle) * closed.frame.l;
    if (plane.u.dot(at_angle) < 0.0) {
      plane.u = -plane.u;
      plane.normal = -plane.normal;
    }
  }
  return sectionFigureSvg(valve_case.mesh, closed.ring, valve_case.tracings, planes, layers,
                          options);
}

}  // namespace chordfit
