#include "core/enface_figure.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <sstream>
#include <vector>

#include "core/carpentier.h"
#include "core/metrics.h"
#include "core/svg_text.h"

namespace chordfit {
namespace {

constexpr double kMarginMm = 4.0;   // around the projected ring
constexpr double kTitlePx = 28.0;   // title row
constexpr double kLegendPx = 84.0;  // legend, height scale, note
// Heights mapped to the lightest shade and above: the highest tissue's, rounded up to an even
// mm, within these bounds (a fixed 4 mm drew a 7.9 mm P2 flap as light as a 3 mm saddle horn).
constexpr double kLightestMinMm = 4.0, kLightestMaxMm = 12.0;
constexpr double kDarkestMm = -12.0;  // ... to the darkest and below
constexpr const char* kOpenColour = "#e0301e";
constexpr const char* kRingColour = "#222222";
// Leaflet colours (Okabe & Ito palette, as the other figures): anterior blue, posterior green.
constexpr int kLeafletRgb[2][3] = {{0x00, 0x72, 0xB2}, {0x00, 0x9E, 0x73}};

// The leaflet colour mixed with white by `lightness` in [0, 1].
std::string shade(int leaflet, double lightness) {
  const int* rgb = kLeafletRgb[leaflet == 0 ? 0 : 1];
  const double t = 0.75 * std::clamp(lightness, 0.0, 1.0);
  char colour[8];
  std::snprintf(
      colour, sizeof colour, "#%02x%02x%02x", static_cast<int>(rgb[0] + t * (255 - rgb[0])),
      static_cast<int>(rgb[1] + t * (255 - rgb[1])), static_cast<int>(rgb[2] + t * (255 - rgb[2])));
  return colour;
}

// The atrial view's screen coordinates (mm): +a (anterior) up, +l (anterolateral) left.
Eigen::Vector2d project(const AnnulusFrame& frame, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - frame.plane.centre;
  return Eigen::Vector2d(-frame.l.dot(d), -frame.a.dot(d));
}

// What the drawing needs of a closure, and what decides the figure's size and scale.
struct EnfaceLayout {
  Eigen::Vector2d lo = Eigen::Vector2d::Zero(), hi = Eigen::Vector2d::Zero();  // frame, mm
  double lightest_mm = kLightestMinMm;  // the height scale's top
  double width = 0.0;                   // px
};

int scaleSteps(double lightest_mm) { return static_cast<int>((lightest_mm - kDarkestMm) / 2.0); }

std::string noteText(double tissue_radius_mm) {
  char note[240];
  std::snprintf(note, sizeof note,
                "atrial view, anterior up, anterolateral commissure left; leaflets drawn "
                "\xC2\xB1 %.2g mm (tissue), the highest on top; prolapse: over 2 mm",
                tissue_radius_mm);
  return note;
}

// Wide enough for the drawing, the legend's height scale (240 px, 22 per swatch, the leaflet
// names, the scale's note), the note under it (about 6 px per character at 11 px) and the
// title (about 7 px per character at 13 px).
double figureWidth(const EnfaceLayout& layout, const EnfaceFigureOptions& options) {
  const double scale_end = 240.0 + 22.0 * (scaleSteps(layout.lightest_mm) + 1) + 60.0 +
                           6.0 * static_cast<double>(options.scale_note.size());
  return std::max({500.0, scale_end,
                   20.0 + 6.0 * static_cast<double>(noteText(options.tissue_radius_mm).size()),
                   (layout.hi.x() - layout.lo.x()) * options.pixels_per_mm,
                   7.0 * static_cast<double>(options.title.size())});
}

// Each triangle's height above the annulus as the prolapse measure has it (the hinge line,
// heightAboveAnnulus: the shade).
std::vector<double> triangleHeights(const ValveCase& valve_case, const ClosedAnnulus& annulus,
                                    const Eigen::MatrixXd& closed_V) {
  const ValveMesh& mesh = valve_case.mesh;
  const Eigen::Index faces = mesh.F.rows();
  Eigen::MatrixXd centroids(faces, 3);
  for (Eigen::Index f = 0; f < faces; ++f)
    centroids.row(f) =
        (closed_V.row(mesh.F(f, 0)) + closed_V.row(mesh.F(f, 1)) + closed_V.row(mesh.F(f, 2))) /
        3.0;
  const Eigen::VectorXd heights = heightAboveAnnulus(annulus.frame, annulus.ring, centroids);
  return std::vector<double>(heights.data(), heights.data() + faces);
}

// The closure's own layout: its ring's frame with a margin, its highest tissue rounded up to
// an even mm within [4, 12] mm as the scale's top.
EnfaceLayout ownLayout(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                       const EnfaceFigureOptions& options) {
  const ValveMesh& mesh = valve_case.mesh;
  const ClosedAnnulus annulus = closedAnnulus(valve_case);
  EnfaceLayout layout;
  layout.lo = Eigen::Vector2d::Constant(1e300), layout.hi = -layout.lo;
  for (Eigen::Index i = 0; i < mesh.annulus.size(); ++i) {
    const Eigen::Vector2d q = project(annulus.frame, closed_V.row(mesh.annulus(i)).transpose());
    layout.lo = layout.lo.cwiseMin(q);
    layout.hi = layout.hi.cwiseMax(q);
  }
  if (mesh.annulus.size() == 0) layout.lo = layout.hi = Eigen::Vector2d::Zero();
  layout.lo -= Eigen::Vector2d::Constant(kMarginMm);
  layout.hi += Eigen::Vector2d::Constant(kMarginMm);
  const std::vector<double> heights = triangleHeights(valve_case, annulus, closed_V);
  const double highest = heights.empty() ? 0.0 : *std::max_element(heights.begin(), heights.end());
  layout.lightest_mm = std::clamp(2.0 * std::ceil(highest / 2.0), kLightestMinMm, kLightestMaxMm);
  layout.width = figureWidth(layout, options);
  return layout;
}

std::string drawEnface(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                       const EnfaceFigureOptions& options, const EnfaceLayout& layout) {
  const ValveMesh& mesh = valve_case.mesh;
  const ClosedAnnulus annulus = closedAnnulus(valve_case);
  const AnnulusFrame& frame = annulus.frame;
  const double s = options.pixels_per_mm;
  const Eigen::MatrixXd ring = closed_V(mesh.annulus, Eigen::all);
  std::vector<Eigen::Vector2d> ring_points;
  for (Eigen::Index i = 0; i < ring.rows(); ++i)
    ring_points.push_back(project(frame, ring.row(i).transpose()));
  const Eigen::Vector2d &lo = layout.lo, &hi = layout.hi;
  // Each triangle's depth along the view (its centroid's signed distance from the closed
  // annulus plane: the drawing order) and its height above the hinge line (the shade).
  const Eigen::Index faces = mesh.F.rows();
  std::vector<double> depths(faces);
  for (Eigen::Index f = 0; f < faces; ++f) {
    const Eigen::Vector3d centroid =
        (closed_V.row(mesh.F(f, 0)) + closed_V.row(mesh.F(f, 1)) + closed_V.row(mesh.F(f, 2)))
            .transpose() /
        3.0;
    depths[f] = frame.plane.signedDistance(centroid);
  }
  const std::vector<double> heights = triangleHeights(valve_case, annulus, closed_V);
  const double lightest_mm = layout.lightest_mm;
  const int steps = scaleSteps(lightest_mm);
  const std::string note = noteText(options.tissue_radius_mm);
  const double width = layout.width;
  const double height = (hi.y() - lo.y()) * s;
  const double left = 0.5 * (width - (hi.x() - lo.x()) * s);
  auto px = [&](const Eigen::Vector2d& q) {
    return Eigen::Vector2d(left + (q.x() - lo.x()) * s, kTitlePx + (q.y() - lo.y()) * s);
  };
  auto points = [&](const std::vector<Eigen::Vector2d>& polygon) {
    std::ostringstream out;
    out.precision(1);
    out << std::fixed;
    for (const Eigen::Vector2d& q : polygon) out << px(q).x() << "," << px(q).y() << " ";
    return out.str();
  };

  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << static_cast<int>(width)
      << "\" height=\"" << static_cast<int>(kTitlePx + height + kLegendPx)
      << "\" font-family=\"sans-serif\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << width / 2 << "\" y=\"18\" text-anchor=\"middle\" font-size=\"13\">"
      << escapeXml(options.title) << "</text>\n";
  svg << "<polygon class=\"orifice\" points=\"" << points(ring_points) << "\" fill=\""
      << kOpenColour << "\"/>\n";

  // Lowest first: the atrial view shows the highest tissue.
  std::vector<Eigen::Index> order(faces);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](Eigen::Index x, Eigen::Index y) { return depths[x] < depths[y]; });
  // The outline grows each triangle by the tissue radius; at least half a pixel so that
  // anti-aliased seams between neighbours do not show the red beneath.
  const double outline_px = std::max(2.0 * options.tissue_radius_mm * s, 0.5);
  svg << "<g class=\"leaflets\" stroke-linejoin=\"round\" stroke-width=\"" << outline_px << "\">\n";
  for (const Eigen::Index f : order) {
    std::vector<Eigen::Vector2d> triangle;
    for (int k = 0; k < 3; ++k)
      triangle.push_back(project(frame, closed_V.row(mesh.F(f, k)).transpose()));
    const int leaflet = mesh.leaflet(mesh.F(f, 0));
    const std::string colour =
        shade(leaflet, (heights[f] - kDarkestMm) / (lightest_mm - kDarkestMm));
    svg << "<polygon points=\"" << points(triangle) << "\" fill=\"" << colour << "\" stroke=\""
        << colour << "\"/>\n";
  }
  svg << "</g>\n<polygon class=\"annulus\" points=\"" << points(ring_points)
      << "\" fill=\"none\" stroke=\"" << kRingColour << "\" stroke-width=\"1.5\"/>\n";

  // Carpentier segment names outside the ring, each beside the middle of its stretch of
  // annulus (its ring points' mean, pushed out from the centre into the margin).
  const Eigen::VectorXi vertex_segment = openStateSegments(mesh);
  std::vector<Eigen::Vector2d> segment_sum(6, Eigen::Vector2d::Zero());
  std::vector<int> segment_count(6, 0);
  for (std::size_t i = 0; i < ring_points.size(); ++i) {
    const int segment = vertex_segment(mesh.annulus(static_cast<Eigen::Index>(i)));
    if (segment < 0 || segment >= 6) continue;
    segment_sum[segment] += ring_points[i];
    ++segment_count[segment];
  }
  // A label beside the ring's side is anchored at its end nearer the ring, so that its width
  // runs away from the leaflets (centred, P1 and P3 touched the tissue drawn past the ring).
  svg << "<g class=\"segments\" font-size=\"11\" fill=\"#222\">\n";
  const double centre_x = px(Eigen::Vector2d::Zero()).x();
  for (int segment = 0; segment < 6; ++segment) {
    if (segment_count[segment] == 0) continue;
    const Eigen::Vector2d middle = segment_sum[segment] / segment_count[segment];
    const Eigen::Vector2d label = middle + 2.5 * middle.normalized();
    const double side =
        (px(label).x() - centre_x) / (px(label) - px(Eigen::Vector2d::Zero())).norm();
    const char* anchor = side > 0.7 ? "start" : side < -0.7 ? "end" : "middle";
    svg << "<text x=\"" << px(label).x() << "\" y=\"" << px(label).y() + 4 << "\" text-anchor=\""
        << anchor << "\">" << escapeXml(segmentName(mesh.leaflet_names, segment)) << "</text>\n";
  }
  svg << "</g>\n";

  // Legend: two rows under the drawing.
  const double y0 = kTitlePx + height + 16.0;
  auto swatch = [&](double x, double y, const std::string& fill, const std::string& label) {
    svg << "<rect x=\"" << x << "\" y=\"" << y - 10 << "\" width=\"14\" height=\"12\" fill=\""
        << fill << "\"/><text x=\"" << x + 20 << "\" y=\"" << y << "\" font-size=\"11\">"
        << escapeXml(label) << "</text>\n";
  };
  const std::string anterior = mesh.leaflet_names.empty() ? "anterior" : mesh.leaflet_names[0];
  const std::string posterior = mesh.leaflet_names.size() < 2 ? "posterior" : mesh.leaflet_names[1];
  swatch(10, y0, shade(0, 0.5), anterior + " leaflet");
  swatch(150, y0, shade(1, 0.5), posterior + " leaflet");
  swatch(290, y0, kOpenColour, "open orifice");
  // Height scale: one swatch per 2 mm of both leaflet shades, labelled every 4 mm.
  const double y1 = y0 + 22.0;
  svg << "<text x=\"10\" y=\"" << y1 << "\" font-size=\"11\">height above the hinge line, mm:"
      << "</text>\n";
  for (int k = 0; k <= steps; ++k) {
    const double x = 240.0 + 22.0 * k, t = static_cast<double>(k) / steps;
    svg << "<rect x=\"" << x << "\" y=\"" << y1 - 10 << "\" width=\"20\" height=\"6\" fill=\""
        << shade(0, t) << "\"/><rect x=\"" << x << "\" y=\"" << y1 - 4
        << "\" width=\"20\" height=\"6\" fill=\"" << shade(1, t) << "\"/>\n";
    if (k % 2 == 0 || k == steps) {  // every 4 mm, and the top (6 or 10 mm with an odd count)
      // The end swatches stand for every height beyond them.
      const std::string prefix = k == 0 ? "\xE2\x89\xA4 " : k == steps ? "\xE2\x89\xA5 " : "";
      svg << "<text x=\"" << x + 10 << "\" y=\"" << y1 + 13
          << "\" font-size=\"10\" text-anchor=\"middle\">" << prefix << kDarkestMm + 2.0 * k
          << "</text>\n";
    }
  }
  const double rows_x = 240.0 + 22.0 * (steps + 1) + 4.0;
  svg << "<text x=\"" << rows_x << "\" y=\"" << y1 - 4 << "\" font-size=\"9\">"
      << escapeXml(anterior) << "</text><text x=\"" << rows_x << "\" y=\"" << y1 + 4
      << "\" font-size=\"9\">" << escapeXml(posterior) << "</text>\n";
  if (!options.scale_note.empty())
    svg << "<text x=\"" << rows_x + 56.0 << "\" y=\"" << y1 << "\" font-size=\"11\" fill=\"#444\">"
        << escapeXml(options.scale_note) << "</text>\n";
  svg << "<text x=\"10\" y=\"" << y1 + 30 << "\" font-size=\"11\" fill=\"#444\">" << note
      << "</text>\n</svg>\n";
  return svg.str();
}

}  // namespace

std::string enfaceFigureSvg(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                            const EnfaceFigureOptions& options) {
  return drawEnface(valve_case, closed_V, options, ownLayout(valve_case, closed_V, options));
}

namespace {

// "<subject>: closed valve from the atrium, orifice N % covered (...); prolapse (tissue): P2".
EnfaceFigureOptions subjectOptions(const std::string& subject, const ValveMetrics& metrics) {
  const OrificeCoverage& orifice = metrics.orifice;
  char coverage[120];
  std::snprintf(coverage, sizeof coverage,
                ": closed valve from the atrium, orifice %.1f %% covered (%.0f of %.0f mm\xC2\xB2 "
                "open)",
                100.0 * orifice.coverage(), orifice.open_area_mm2, orifice.orifice_area_mm2);
  std::string prolapse = "; no prolapse";
  for (std::size_t i = 0; i < metrics.mesh_prolapse.segments.size(); ++i)
    prolapse =
        (i == 0 ? "; prolapse (tissue): " : prolapse + ", ") + metrics.mesh_prolapse.segments[i];
  EnfaceFigureOptions options;
  options.title = subject + coverage + prolapse;
  options.tissue_radius_mm = orifice.tissue_radius_mm;
  return options;
}

}  // namespace

std::string enfaceFigureSvg(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                            const std::string& subject, const ValveMetrics& metrics) {
  return enfaceFigureSvg(valve_case, closed_V, subjectOptions(subject, metrics));
}

std::vector<std::string> enfaceFiguresSvg(const ValveCase& valve_case,
                                          const std::vector<EnfaceClosure>& closures) {
  std::vector<EnfaceFigureOptions> options;
  EnfaceLayout shared;
  for (const EnfaceClosure& closure : closures) {
    options.push_back(subjectOptions(closure.subject, closure.metrics));
    options.back().scale_note =
        "(one scale for all " + std::to_string(closures.size()) + " figures)";
    const EnfaceLayout own = ownLayout(valve_case, closure.closed_V, options.back());
    if (options.size() == 1) {
      shared = own;
      continue;
    }
    shared.lo = shared.lo.cwiseMin(own.lo);
    shared.hi = shared.hi.cwiseMax(own.hi);
    shared.lightest_mm = std::max(shared.lightest_mm, own.lightest_mm);
  }
  // The width of the widest figure at the shared frame and scale.
  shared.width = 0.0;
  for (const EnfaceFigureOptions& o : options)
    shared.width = std::max(shared.width, figureWidth(shared, o));
  std::vector<std::string> figures;
  for (std::size_t i = 0; i < closures.size(); ++i)
    figures.push_back(drawEnface(valve_case, closures[i].closed_V, options[i], shared));
  return figures;
}

}  // namespace chordfit
