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

}  // namespace

std::string enfaceFigureSvg(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                            const EnfaceFigureOptions& options) {
  const ValveMesh& mesh = valve_case.mesh;
  const ClosedAnnulus annulus = closedAnnulus(valve_case);
  const AnnulusFrame& frame = annulus.frame;
  const double s = options.pixels_per_mm;
  // Screen coordinates of the atrial view: +a (anterior) up, +l (anterolateral) left.
  auto project = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = p - frame.plane.centre;
    return Eigen::Vector2d(-frame.l.dot(d), -frame.a.dot(d));
  };
  const Eigen::MatrixXd ring = closed_V(mesh.annulus, Eigen::all);
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300), hi = -lo;
  std::vector<Eigen::Vector2d> ring_points;
  for (Eigen::Index i = 0; i < ring.rows(); ++i) {
    ring_points.push_back(project(ring.row(i).transpose()));
    lo = lo.cwiseMin(ring_points.back());
    hi = hi.cwiseMax(ring_points.back());
  }
  if (ring_points.empty()) lo = hi = Eigen::Vector2d::Zero();
  lo -= Eigen::Vector2d::Constant(kMarginMm);
  hi += Eigen::Vector2d::Constant(kMarginMm);
  // Each triangle's depth along the view (its centroid's signed distance from the closed
  // annulus plane: the drawing order) and its height above the annulus as the prolapse measure
  // has it (the hinge line, heightAboveAnnulus: the shade), and the scale's top.
  const Eigen::Index faces = mesh.F.rows();
  Eigen::MatrixXd centroids(faces, 3);
  std::vector<double> depths(faces);
  for (Eigen::Index f = 0; f < faces; ++f) {
    centroids.row(f) =
        (closed_V.row(mesh.F(f, 0)) + closed_V.row(mesh.F(f, 1)) + closed_V.row(mesh.F(f, 2))) /
        3.0;
    depths[f] = frame.plane.signedDistance(centroids.row(f).transpose());
  }
  const Eigen::VectorXd hinge_heights = heightAboveAnnulus(frame, annulus.ring, centroids);
  const std::vector<double> heights(hinge_heights.data(), hinge_heights.data() + faces);
  const double highest = faces > 0 ? *std::max_element(heights.begin(), heights.end()) : 0.0;
  const double lightest_mm =
      std::clamp(2.0 * std::ceil(highest / 2.0), kLightestMinMm, kLightestMaxMm);
  const int steps = static_cast<int>((lightest_mm - kDarkestMm) / 2.0);
  char note[240];
  std::snprintf(note, sizeof note,
                "atrial view, anterior up, anterolateral commissure left; leaflets drawn "
                "\xC2\xB1 %.2g mm (tissue), the highest on top; prolapse: over 2 mm",
                options.tissue_radius_mm);
  // Wide enough for the legend's height scale (240 px, 22 per swatch, the leaflet names), the
  // note under it (about 6 px per character at 11 px) and the title (about 7 px per character
  // at 13 px).
  const double width =
      std::max({500.0, 240.0 + 22.0 * (steps + 1) + 60.0, 20.0 + 6.0 * std::strlen(note),
                (hi.x() - lo.x()) * s, 7.0 * static_cast<double>(options.title.size())});
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
    for (int k = 0; k < 3; ++k) triangle.push_back(project(closed_V.row(mesh.F(f, k)).transpose()));
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
  svg << "<g class=\"segments\" font-size=\"11\" fill=\"#222\" text-anchor=\"middle\">\n";
  for (int segment = 0; segment < 6; ++segment) {
    if (segment_count[segment] == 0) continue;
    const Eigen::Vector2d middle = segment_sum[segment] / segment_count[segment];
    const Eigen::Vector2d label = middle + 2.5 * middle.normalized();
    svg << "<text x=\"" << px(label).x() << "\" y=\"" << px(label).y() + 4 << "\">"
        << escapeXml(segmentName(mesh.leaflet_names, segment)) << "</text>\n";
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
  svg << "<text x=\"10\" y=\"" << y1 + 30 << "\" font-size=\"11\" fill=\"#444\">" << note
      << "</text>\n</svg>\n";
  return svg.str();
}

std::string enfaceFigureSvg(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                            const std::string& subject, const ValveMetrics& metrics) {
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
  return enfaceFigureSvg(valve_case, closed_V,
                         {subject + coverage + prolapse, orifice.tissue_radius_mm});
}

}  // namespace chordfit
