// Parametric open-state mitral valve (see parametric_valve.h for the frame).
//
// Construction, in order:
//  1. Annulus curve. Default: the saddle ellipse
//       x = (ap/2) cos(phi), y = (cc/2) sin(phi), z = (h/2) cos(2 phi),
//     highs at the anterior (phi = 0) and posterior (phi = pi) midpoints, lows at the
//     commissures (Levine et al., Circulation 1989;80:589; Salgo et al., Circulation
//     2002;106:711). Or a user polyline (see "User annulus" below).
//  2. Columns. N = max(kMinColumns, round(perimeter / target_edge)) points at equal 3D arc
//     length, starting at the anterior midpoint and running counter-clockwise seen from the
//     atrium (+x -> +y -> -x -> -y), i.e. from A2 toward the anterolateral commissure.
//  3. Leaflets. The anterior leaflet is the arc of length anterior_fraction * perimeter
//     centred on the start; the rest is posterior. The commissures are the two ends of that
//     arc. Carpentier segments are equal angular thirds of each leaflet's arc, angles
//     measured about the ring centroid in the annulus plane (as core/carpentier.h does), so
//     a geometric assignment by angle reproduces ours.
//  4. Leaflet height H(theta) along the annulus, theta = polar angle of the column: a C1
//     piecewise curve with zero slope at every knot, rounded toward the maxima (see
//     roundedRise) through the knots
//       PM commissure  commissural_height
//       A2 centre      anterior_height
//       AL commissure  commissural_height
//       P1 centre      posterior_side_height
//       P1/P2 cleft    (1 - indentation_depth) * (posterior_side_height + posterior_height)/2
//       P2 centre      posterior_height
//       P2/P3 cleft    as P1/P2
//       P3 centre      posterior_side_height
//       PM commissure  commissural_height (periodic).
//     Clefts sit at the boundaries of the posterior angular thirds and keep a positive
//     height, so they never reach the annulus.
//  5. Meridians. From annulus point A the leaflet runs down (-n) and inward (toward the
//     ring centre, radially in the annulus plane, so polar angles are preserved) along a
//     planar curve parametrised by arc length s in [0, H] whose tilt from the vertical
//     grows linearly from kTiltAtAnnulus to kTiltAtFreeEdge (constant curvature, a gentle
//     belly bulging away from the axis as in diastolic inflow; 12 -> 30 degrees):
//       alpha(s) = a0 + k s,  k = (a1 - a0) / H,
//       inward(s) = (cos a0 - cos(a0 + k s)) / k,  down(s) = (sin(a0 + k s) - sin a0) / k.
//     Since |d(inward, down)/ds| = 1, the leaflet heights are true lengths. The free-edge
//     tilt was tuned so that, with the defaults, the projected orifice is 4.1 cm^2 = 53% of
//     the 7.7 cm^2 projected annulus (4.3 cm^2 = 55% since the clefts went from 0.5 to 0.8
//     of the scallop height): inside the normal mitral valve area of 4-6 cm^2 and
//     still clearly narrower than the annulus. Larger tilts shrink the anterior free edge's
//     column spacing (radial convergence) below ~0.4 target edge.
//  6. Mesh. Each column gets vertices at s = 0, e, 2e, ... plus the free-edge vertex at H
//     (the last interior one is dropped if closer than e/2 to H). Neighbouring columns are
//     stitched by a zipper that advances the side whose next vertex has the lower s (ties:
//     the left column), closing periodically. The result is a tube: one boundary loop is
//     the annulus, the other the free edge.
//
// Vertex layout (relied upon by tests and handy for callers): vertices are stored column by
// column; column k holds annulus[k] followed by its meridian vertices down to free_edge[k],
// so the indices annulus[k] .. free_edge[k] are exactly column k, in order of arc length.
//
// Orientation: face normals point from the ventricular to the atrial side, i.e. toward the
// valve axis (the inside of the open funnel, which faces the atrium).
//
// User annulus (ValveParameters::annulus_polyline): the polyline must be given in the same
// anatomical frame convention as the parametric valve, approximately: anterior toward +x,
// atrium toward +z. Its exact plane is fitted by PCA (the normal oriented to +z), the
// anterior axis is +x projected into that plane. The loop is reversed if needed so that it
// runs counter-clockwise seen from the atrium, and the ring starts where the loop crosses the
// anterior half-axis (from the vertex centroid). It must be star-shaped about its centroid.
// Output positions stay in the caller's coordinates; the leaflets hang along the fitted
// normal. The closed annulus is derived by contracting in-plane offsets from the ring
// centroid by closed_contraction and scaling out-of-plane offsets by
// closed_saddle_height / saddle_height (1 if saddle_height is 0).
//
// Default parameters (parametric_valve.h) and sources:
//  - ap 28 mm, cc 35 mm: normal adult annulus (Kaplan et al., Am Heart J 2000;139:378,
//    3D echo of normal valves; cc/ap ~ 1.25-1.3).
//  - saddle height 5 mm open, 7 mm closed: annular height / commissural width ~15-20% in
//    systole in normals (Salgo et al. 2002); the saddle deepens in systole (Levine 1989).
//  - closed_contraction 0.9 -> ~19% systolic area reduction (Ormiston et al., Circulation
//    1981;64:113 report a ~25% reduction of annular area from its diastolic maximum).
//  - anterior_fraction 1/3 of the circumference; anterior height 23 mm, posterior 14 mm
//    (P2), side scallops ~11 mm, commissural leaflets ~8 mm (Ranganathan et al.,
//    Circulation 1970;41:459: anterior leaflet about twice as high as the posterior one,
//    middle posterior scallop the largest).
//  - tilt 12 deg at the annulus (open funnel, Ho, Heart 2002;88 Suppl IV:iv5 describes the
//    open leaflets as a funnel from the hinge line to the free margins).
#include "core/parametric_valve.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace chordfit {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;
// Meridian tilt from the annulus-plane normal at the annulus and at the free edge.
constexpr double kTiltAtAnnulus = 12.0 * kDegree;
constexpr double kTiltAtFreeEdge = 30.0 * kDegree;
// Fewest columns: every Carpentier segment gets at least one column.
constexpr int kMinColumns = 12;
// Samples of the dense table used to invert the ellipse's arc length.
constexpr int kArcTableSamples = 1 << 14;
// The free edge must keep at least this fraction of a column's radial distance from the
// axis; more would fold the leaflet across the orifice.
constexpr double kMinFreeEdgeRadiusFraction = 0.2;

// ---------------------------------------------------------------------------------------
// Parameter validation
// ---------------------------------------------------------------------------------------

std::string formatNumber(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// `why`: where a bound comes from when other parameters set it, e.g. " (half ...)".
void requireInRange(const char* name, double value, double lo, double hi, bool lo_open,
                    bool hi_open, const std::string& why = "") {
  const bool ok = std::isfinite(value) && (lo_open ? value > lo : value >= lo) &&
                  (hi_open ? value < hi : value <= hi);
  if (!ok) {
    throw std::invalid_argument(std::string(name) + " must be in " + (lo_open ? "(" : "[") +
                                formatNumber(lo) + ", " + formatNumber(hi) + (hi_open ? ")" : "]") +
                                why + ", got " + formatNumber(value));
  }
}

void requirePositive(const char* name, double value) {
  if (!(std::isfinite(value) && value > 0.0)) {
    throw std::invalid_argument(std::string(name) + " must be positive and finite, got " +
                                formatNumber(value));
  }
}

void validatePolyline(const Eigen::MatrixXd& P) {
  if (P.cols() != 3) {
    throw std::invalid_argument("annulus_polyline must have 3 columns, got " +
                                std::to_string(P.cols()));
  }
  if (P.rows() < 8) {
    throw std::invalid_argument("annulus_polyline must have at least 8 points, got " +
                                std::to_string(P.rows()));
  }
  if (!P.allFinite()) {
    throw std::invalid_argument("annulus_polyline has non-finite values");
  }
  // Checked before meshing: an annulus in micrometres was meshed at the target edge first
  // (10^5 times the vertices, until memory ran out), then refused.
  const double span = (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm();
  if (!(span >= kMinAnnulusSpanMm && span <= kMaxAnnulusSpanMm)) {
    throw std::invalid_argument(
        "annulus_polyline spans " + formatNumber(span) +
        " mm (bounding-box diagonal); a mitral annulus spans about 35-50 mm and coordinates "
        "must be in millimetres (accepted: " +
        formatNumber(kMinAnnulusSpanMm) + " to " + formatNumber(kMaxAnnulusSpanMm) + " mm)");
  }
}

void validateParameters(const ValveParameters& p) {
  // Diameters: a mitral annulus is a few centimetres; 100 mm is far beyond any dilatation.
  requireInRange("ap_diameter_mm", p.ap_diameter_mm, 0.0, 100.0, true, false);
  requireInRange("cc_diameter_mm", p.cc_diameter_mm, 0.0, 100.0, true, false);
  // Saddle heights: 0 (flat) up to half the smaller diameter. The message names the
  // diameters: a small --cc makes the default heights too tall, and naming only the height
  // blamed a value the user never gave.
  // With an annulus polyline the diameters do not act and the heights only through their
  // ratio (closedPolylineRing): bounded as the polyline's span is.
  const bool polyline = p.annulus_polyline.has_value();
  const double max_saddle =
      polyline ? 0.5 * kMaxAnnulusSpanMm : 0.5 * std::min(p.ap_diameter_mm, p.cc_diameter_mm);
  const std::string saddle_bound =
      polyline ? " (with annulus_polyline only the closed/open ratio acts)"
               : " (half the smaller of ap_diameter_mm " + formatNumber(p.ap_diameter_mm) +
                     " and cc_diameter_mm " + formatNumber(p.cc_diameter_mm) + ")";
  requireInRange("saddle_height_mm", p.saddle_height_mm, 0.0, max_saddle, false, false,
                 saddle_bound);
  requireInRange("closed_saddle_height_mm", p.closed_saddle_height_mm, 0.0, max_saddle, false,
                 false, saddle_bound);
  requireInRange("closed_contraction", p.closed_contraction, 0.5, 1.5, false, false);
  requireInRange("anterior_fraction", p.anterior_fraction, 0.15, 0.6, true, true);
  requirePositive("anterior_height_mm", p.anterior_height_mm);
  requirePositive("posterior_height_mm", p.posterior_height_mm);
  requirePositive("posterior_side_height_mm", p.posterior_side_height_mm);
  requirePositive("commissural_height_mm", p.commissural_height_mm);
  requireInRange("indentation_depth", p.indentation_depth, 0.0, 0.9, false, false);
  requireInRange("target_edge_mm", p.target_edge_mm, 0.2, 10.0, false, false);
  if (p.annulus_polyline) validatePolyline(*p.annulus_polyline);
}

// ---------------------------------------------------------------------------------------
// Annulus curves: a closed curve sampled by arc length s from the anterior midpoint,
// counter-clockwise seen from the atrium.
// ---------------------------------------------------------------------------------------

struct AnnulusCurve {
  double perimeter = 0.0;
  std::function<Eigen::Vector3d(double)> at;  // position at arc length s (any real s)
};

double wrapArc(double s, double perimeter) {
  double w = std::fmod(s, perimeter);
  if (w < 0.0) w += perimeter;
  return w;
}

// Saddle ellipse point at parameter phi.
Eigen::Vector3d saddlePoint(const ValveParameters& p, double phi) {
  return {0.5 * p.ap_diameter_mm * std::cos(phi), 0.5 * p.cc_diameter_mm * std::sin(phi),
          0.5 * p.saddle_height_mm * std::cos(2.0 * phi)};
}

// Dense table phi_j = 2 pi j / M with cumulative 3D chord length s_j; phi(s) by linear
// interpolation. The positions are evaluated from phi exactly, so they lie on the saddle;
// only the spacing carries the (tiny, O(M^-2)) table error.
struct EllipseArcTable {
  std::vector<double> s;  // M + 1 entries, s[0] = 0, s[M] = perimeter

  explicit EllipseArcTable(const ValveParameters& p) : s(kArcTableSamples + 1, 0.0) {
    Eigen::Vector3d prev = saddlePoint(p, 0.0);
    for (int j = 1; j <= kArcTableSamples; ++j) {
      const Eigen::Vector3d cur = saddlePoint(p, 2.0 * kPi * j / kArcTableSamples);
      s[j] = s[j - 1] + (cur - prev).norm();
      prev = cur;
    }
  }

  double perimeter() const { return s.back(); }

  double phiAt(double arc) const {
    const double w = wrapArc(arc, perimeter());
    const auto it = std::upper_bound(s.begin(), s.end(), w);
    const int j = std::clamp(static_cast<int>(it - s.begin()) - 1, 0, kArcTableSamples - 1);
    const double t = (w - s[j]) / (s[j + 1] - s[j]);
    return 2.0 * kPi * (j + t) / kArcTableSamples;
  }
};

// Least-squares plane normal of the rows of P (PCA, smallest eigenvalue), oriented to +z.
Eigen::Vector3d fittedNormalTowardZ(const Eigen::MatrixXd& P) {
  const Eigen::RowVector3d centroid = P.colwise().mean();
  const Eigen::MatrixXd Q = P.rowwise() - centroid;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(Q.transpose() * Q);
  if (solver.eigenvalues()(1) <= 1e-12 * std::max(1.0, solver.eigenvalues()(2))) {
    throw std::invalid_argument("annulus_polyline is degenerate (collinear points)");
  }
  Eigen::Vector3d n = solver.eigenvectors().col(0);
  if (std::abs(n.z()) < 0.1) {
    throw std::invalid_argument(
        "annulus_polyline plane is nearly parallel to z; give it with the atrium toward +z");
  }
  return n.z() < 0.0 ? Eigen::Vector3d(-n) : n;
}

// In-plane anterior axis: +x projected into the plane of normal n.
Eigen::Vector3d anteriorAxis(const Eigen::Vector3d& n) {
  const Eigen::Vector3d a = Eigen::Vector3d::UnitX() - n.x() * n;
  if (a.norm() < 0.1) {
    throw std::invalid_argument(
        "annulus_polyline plane is nearly perpendicular to x; give it with anterior toward +x");
  }
  return a.normalized();
}

// Closed polyline with cumulative arc lengths, start shifted to `start`.
struct PolylineCurve {
  Eigen::MatrixXd P;      // #P by 3, consecutive duplicates removed
  std::vector<double> s;  // #P + 1 cumulative lengths (closing segment included)
  double start = 0.0;     // arc length of the anterior crossing

  Eigen::Vector3d at(double arc) const {
    const double w = wrapArc(arc + start, s.back());
    const auto it = std::upper_bound(s.begin(), s.end(), w);
    const int n = static_cast<int>(P.rows());
    const int j = std::clamp(static_cast<int>(it - s.begin()) - 1, 0, n - 1);
    const double t = (w - s[j]) / (s[j + 1] - s[j]);
    return (1.0 - t) * P.row(j).transpose() + t * P.row((j + 1) % n).transpose();
  }
};

Eigen::MatrixXd withoutRepeatedPoints(const Eigen::MatrixXd& P) {
  std::vector<int> keep;
  for (int i = 0; i < P.rows(); ++i) {
    const int prev = keep.empty() ? -1 : keep.back();
    if (prev >= 0 && (P.row(i) - P.row(prev)).norm() <= 1e-12) continue;
    keep.push_back(i);
  }
  while (keep.size() > 1 && (P.row(keep.back()) - P.row(keep.front())).norm() <= 1e-12) {
    keep.pop_back();
  }
  Eigen::MatrixXd out(keep.size(), 3);
  for (size_t i = 0; i < keep.size(); ++i) out.row(i) = P.row(keep[i]);
  if (out.rows() < 8) {
    throw std::invalid_argument("annulus_polyline must have at least 8 distinct points, got " +
                                std::to_string(out.rows()));
  }
  return out;
}

// Signed area of the loop projected on the plane (a, l); positive = counter-clockwise
// seen from the +n side.
double signedPlaneArea(const Eigen::MatrixXd& P, const Eigen::Vector3d& a,
                       const Eigen::Vector3d& l) {
  double area = 0.0;
  for (int i = 0; i < P.rows(); ++i) {
    const Eigen::Vector3d p = P.row(i).transpose();
    const Eigen::Vector3d q = P.row((i + 1) % P.rows()).transpose();
    area += 0.5 * (a.dot(p) * l.dot(q) - a.dot(q) * l.dot(p));
  }
  return area;
}

PolylineCurve makePolylineCurve(const Eigen::MatrixXd& input) {
  PolylineCurve curve;
  curve.P = withoutRepeatedPoints(input);
  const Eigen::Vector3d n = fittedNormalTowardZ(curve.P);
  const Eigen::Vector3d a = anteriorAxis(n);
  const Eigen::Vector3d l = n.cross(a);
  if (signedPlaneArea(curve.P, a, l) < 0.0) curve.P = curve.P.colwise().reverse().eval();

  const int count = static_cast<int>(curve.P.rows());
  curve.s.assign(count + 1, 0.0);
  for (int i = 0; i < count; ++i) {
    curve.s[i + 1] = curve.s[i] + (curve.P.row((i + 1) % count) - curve.P.row(i)).norm();
  }
  // Start: where the loop crosses the anterior half-axis (v = 0, u > 0) going to v > 0.
  const Eigen::Vector3d c = curve.P.colwise().mean().transpose();
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p = curve.P.row(i).transpose() - c;
    const Eigen::Vector3d q = curve.P.row((i + 1) % count).transpose() - c;
    const double vp = l.dot(p), vq = l.dot(q);
    if (!(vp < 0.0 && vq >= 0.0)) continue;
    const double t = vp / (vp - vq);
    if (a.dot((1.0 - t) * p + t * q) <= 0.0) continue;
    curve.start = curve.s[i] + t * (curve.s[i + 1] - curve.s[i]);
    return curve;
  }
  throw std::invalid_argument(
      "annulus_polyline does not cross its anterior (+x) half-axis; it must be a loop around "
      "its centroid");
}

AnnulusCurve ellipseCurve(const ValveParameters& p) {
  auto table = std::make_shared<EllipseArcTable>(p);
  AnnulusCurve curve;
  curve.perimeter = table->perimeter();
  curve.at = [table, p](double arc) { return saddlePoint(p, table->phiAt(arc)); };
  return curve;
}

AnnulusCurve polylineCurve(const Eigen::MatrixXd& P) {
  auto polyline = std::make_shared<PolylineCurve>(makePolylineCurve(P));
  AnnulusCurve curve;
  curve.perimeter = polyline->s.back();
  curve.at = [polyline](double arc) { return polyline->at(arc); };
  return curve;
}

// ---------------------------------------------------------------------------------------
// Ring: columns' annulus points, frame, leaflets, segments, heights.
// ---------------------------------------------------------------------------------------

struct RingFrame {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // centroid of the ring points
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ();      // toward the atrium
  Eigen::Vector3d a = Eigen::Vector3d::UnitX();      // anterior
  Eigen::Vector3d l = Eigen::Vector3d::UnitY();      // anterolateral, n x a

  double angle(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - centre;
    return std::atan2(l.dot(d), a.dot(d));
  }
  // In-plane unit vector from the centre toward p.
  Eigen::Vector3d radial(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - centre;
    return (d - n.dot(d) * n).normalized();
  }
  double radius(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - centre;
    return (d - n.dot(d) * n).norm();
  }
};

RingFrame ringFrame(const Eigen::MatrixXd& ring, bool parametric) {
  RingFrame frame;
  frame.centre = ring.colwise().mean().transpose();
  if (!parametric) {  // parametric: the frame is the coordinate frame by construction
    frame.n = fittedNormalTowardZ(ring);
    frame.a = anteriorAxis(frame.n);
    frame.l = frame.n.cross(frame.a);
  }
  return frame;
}

// Commissure angles and the knots of the C1 height profile, over the angle range
// [theta_pm, theta_pm + 2 pi): anterior arc [theta_pm, theta_al], posterior arc after it.
struct LeafletLayout {
  double theta_al = 0.0;                     // anterolateral commissure, in (0, pi)
  double theta_pm = 0.0;                     // posteromedial commissure, in (-pi, 0)
  std::vector<std::array<double, 2>> knots;  // (angle, height), increasing angle, periodic

  double anteriorSweep() const { return theta_al - theta_pm; }
  double posteriorSweep() const { return 2.0 * kPi - anteriorSweep(); }
  // Angle mapped into [theta_pm, theta_pm + 2 pi).
  double unwrap(double theta) const {
    double t = theta;
    while (t < theta_pm) t += 2.0 * kPi;
    while (t >= theta_pm + 2.0 * kPi) t -= 2.0 * kPi;
    return t;
  }
};

LeafletLayout leafletLayout(const ValveParameters& p, double theta_al, double theta_pm) {
  if (!(theta_al > 0.0 && theta_al < kPi && theta_pm < 0.0 && theta_pm > -kPi)) {
    throw std::invalid_argument(
        "annulus_polyline: commissures must lie on either side of the anteroposterior axis "
        "(anterior toward +x, anterolateral toward +y)");
  }
  LeafletLayout layout;
  layout.theta_al = theta_al;
  layout.theta_pm = theta_pm;
  const double sp = layout.posteriorSweep();
  const double cleft =
      (1.0 - p.indentation_depth) * 0.5 * (p.posterior_side_height_mm + p.posterior_height_mm);
  layout.knots = {
      {theta_pm, p.commissural_height_mm},
      {0.5 * (theta_pm + theta_al), p.anterior_height_mm},
      {theta_al, p.commissural_height_mm},
      {theta_al + sp / 6.0, p.posterior_side_height_mm},
      {theta_al + sp / 3.0, cleft},
      {theta_al + sp / 2.0, p.posterior_height_mm},
      {theta_al + 2.0 * sp / 3.0, cleft},
      {theta_al + 5.0 * sp / 6.0, p.posterior_side_height_mm},
      {theta_pm + 2.0 * kPi, p.commissural_height_mm},
  };
  return layout;
}

// Rise from 0 to 1 over w in [0, 1] with zero slope at both ends, rounded at the top:
// r(w) = 1 - (1 - S(w))^2 with the smoothstep S(w) = 3w^2 - 2w^3. Compared with S alone it
// keeps the leaflet high over a wider stretch (scallops and the anterior leaflet are
// rounded festoons) and pinches the minima (commissures, clefts), while staying C1.
double roundedRise(double w) {
  const double smooth = w * w * (3.0 - 2.0 * w);
  return 1.0 - (1.0 - smooth) * (1.0 - smooth);
}

// C1 height profile through the knots: between two knots the height rises from the lower
// to the higher one by roundedRise (zero slope at every knot).
double leafletHeight(const LeafletLayout& layout, double theta) {
  const double t = layout.unwrap(theta);
  for (size_t i = 0; i + 1 < layout.knots.size(); ++i) {
    const auto& [t0, h0] = layout.knots[i];
    const auto& [t1, h1] = layout.knots[i + 1];
    if (t > t1) continue;
    const double u = std::clamp((t - t0) / (t1 - t0), 0.0, 1.0);
    return h1 >= h0 ? h0 + (h1 - h0) * roundedRise(u) : h1 + (h0 - h1) * roundedRise(1.0 - u);
  }
  return layout.knots.back()[1];
}

// Fraction of angle theta along its leaflet's arc, 0 at the anterolateral commissure.
double arcFraction(const LeafletLayout& layout, int leaflet, double theta) {
  const double t = layout.unwrap(theta);
  return leaflet == 0 ? (layout.theta_al - t) / layout.anteriorSweep()
                      : (t - layout.theta_al) / layout.posteriorSweep();
}

// Carpentier index 0..2 within the leaflet, counted from the anterolateral commissure.
int segmentIndex(const LeafletLayout& layout, int leaflet, double theta) {
  const double fraction = arcFraction(layout, leaflet, theta);
  return std::clamp(static_cast<int>(std::floor(3.0 * fraction)), 0, 2);
}

struct Column {
  Eigen::Vector3d annulus;
  double height = 0.0;
  int leaflet = 0;
  int segment = 0;        // global id leaflet * 3 + index
  double fraction = 0.0;  // along the leaflet's arc (arcFraction)
};

struct Ring {
  RingFrame frame;
  std::vector<Column> columns;
  Eigen::MatrixXd open;  // #columns by 3
};

// Polar angles must increase around the ring and wind exactly once; otherwise angles (and
// hence heights and segments) are not a function of the position along the ring.
void requireStarShaped(const Ring& ring) {
  const int count = static_cast<int>(ring.columns.size());
  double winding = 0.0;
  for (int k = 0; k < count; ++k) {
    const double step = std::remainder(ring.frame.angle(ring.columns[(k + 1) % count].annulus) -
                                           ring.frame.angle(ring.columns[k].annulus),
                                       2.0 * kPi);
    if (!(step > 0.0)) {
      throw std::invalid_argument(
          "annulus_polyline must be star-shaped about its centroid (polar angle must "
          "increase monotonically around the loop)");
    }
    winding += step;
  }
  if (std::abs(winding - 2.0 * kPi) > 1e-6) {
    throw std::invalid_argument("annulus_polyline must wind once around its centroid");
  }
}

Ring buildRing(const ValveParameters& p, const AnnulusCurve& curve, bool parametric) {
  const int count =
      std::max(kMinColumns, static_cast<int>(std::lround(curve.perimeter / p.target_edge_mm)));
  const double spacing = curve.perimeter / count;
  Ring ring;
  ring.open.resize(count, 3);
  for (int k = 0; k < count; ++k) ring.open.row(k) = curve.at(k * spacing).transpose();
  ring.frame = ringFrame(ring.open, parametric);

  // Commissures: ends of the anterior arc of length anterior_fraction * perimeter.
  const double half_anterior = 0.5 * p.anterior_fraction * curve.perimeter;
  const LeafletLayout layout =
      leafletLayout(p, ring.frame.angle(curve.at(half_anterior)),
                    ring.frame.angle(curve.at(curve.perimeter - half_anterior)));

  ring.columns.resize(count);
  for (int k = 0; k < count; ++k) {
    Column& column = ring.columns[k];
    column.annulus = ring.open.row(k).transpose();
    const double arc = k * spacing;
    const double signed_arc = arc <= 0.5 * curve.perimeter ? arc : arc - curve.perimeter;
    column.leaflet = std::abs(signed_arc) < half_anterior ? 0 : 1;
    const double theta = ring.frame.angle(column.annulus);
    column.height = leafletHeight(layout, theta);
    column.segment = 3 * column.leaflet + segmentIndex(layout, column.leaflet, theta);
    column.fraction = arcFraction(layout, column.leaflet, theta);
  }
  requireStarShaped(ring);
  return ring;
}

// ---------------------------------------------------------------------------------------
// Meridians and mesh
// ---------------------------------------------------------------------------------------

// (inward, down) offsets at arc length s along a meridian of length `height`.
Eigen::Vector2d meridianOffset(double s, double height) {
  const double k = (kTiltAtFreeEdge - kTiltAtAnnulus) / height;
  const double alpha = kTiltAtAnnulus + k * s;
  return {(std::cos(kTiltAtAnnulus) - std::cos(alpha)) / k,
          (std::sin(alpha) - std::sin(kTiltAtAnnulus)) / k};
}

// Arc-length stations of a column: 0, e, 2e, ... (dropping one closer than e/2 to H), H.
std::vector<double> columnStations(double height, double edge) {
  std::vector<double> stations{0.0};
  for (int j = 1; j * edge <= height - 0.5 * edge; ++j) stations.push_back(j * edge);
  stations.push_back(height);
  return stations;
}

void checkFreeEdgeRadius(const RingFrame& frame, const Column& column, int index) {
  const double inward = meridianOffset(column.height, column.height).x();
  const double radius = frame.radius(column.annulus);
  if (inward > (1.0 - kMinFreeEdgeRadiusFraction) * radius) {
    throw std::invalid_argument(
        std::string("leaflet heights too large for the annulus: the free edge of column ") +
        std::to_string(index) + " (" + (column.leaflet == 0 ? "anterior" : "posterior") +
        ", height " + formatNumber(column.height) +
        " mm) would reach the valve axis (annulus radius " + formatNumber(radius) +
        " mm); reduce the leaflet height there (anterior_height_mm, posterior_height_mm, "
        "posterior_side_height_mm and commissural_height_mm set it along the annulus) or "
        "enlarge the annulus");
  }
}

struct ColumnVertices {
  std::vector<double> s;  // arc-length stations
  int first = 0;          // index of the annulus vertex; the column is first .. first+size-1
};

// Appends triangles stitching column `left` to the next column `right` (counter-clockwise).
// Triangles (L_a, R_b, L_a+1) and (L_a, R_b, R_b+1) have normals toward the axis.
void zipColumns(const ColumnVertices& left, const ColumnVertices& right,
                std::vector<Eigen::Vector3i>& faces) {
  const int nl = static_cast<int>(left.s.size());
  const int nr = static_cast<int>(right.s.size());
  int a = 0, b = 0;
  while (a < nl - 1 || b < nr - 1) {
    const bool advance_left = b == nr - 1 || (a < nl - 1 && left.s[a + 1] <= right.s[b + 1]);
    if (advance_left) {
      faces.emplace_back(left.first + a, right.first + b, left.first + a + 1);
      ++a;
    } else {
      faces.emplace_back(left.first + a, right.first + b, right.first + b + 1);
      ++b;
    }
  }
}

void buildMesh(const Ring& ring, double edge, ParametricValve& valve) {
  const int count = static_cast<int>(ring.columns.size());
  std::vector<ColumnVertices> columns(count);
  int total = 0;
  for (int k = 0; k < count; ++k) {
    checkFreeEdgeRadius(ring.frame, ring.columns[k], k);
    columns[k].s = columnStations(ring.columns[k].height, edge);
    columns[k].first = total;
    total += static_cast<int>(columns[k].s.size());
  }

  ValveMesh& mesh = valve.valve_case.mesh;
  mesh.V.resize(total, 3);
  mesh.leaflet.resize(total);
  valve.segment.resize(total);
  mesh.annulus.resize(count);
  valve.free_edge.resize(count);
  valve.column_fraction.resize(count);
  for (int k = 0; k < count; ++k) {
    const Column& column = ring.columns[k];
    const Eigen::Vector3d inward = -ring.frame.radial(column.annulus);
    const Eigen::Vector3d down = -ring.frame.n;
    for (size_t j = 0; j < columns[k].s.size(); ++j) {
      const int v = columns[k].first + static_cast<int>(j);
      const Eigen::Vector2d offset = meridianOffset(columns[k].s[j], column.height);
      mesh.V.row(v) =
          (j == 0 ? column.annulus
                  : Eigen::Vector3d(column.annulus + offset.x() * inward + offset.y() * down))
              .transpose();
      mesh.leaflet(v) = column.leaflet;
      valve.segment(v) = column.segment;
    }
    mesh.annulus(k) = columns[k].first;
    valve.free_edge(k) = columns[k].first + static_cast<int>(columns[k].s.size()) - 1;
    valve.column_fraction(k) = column.fraction;
  }

  std::vector<Eigen::Vector3i> faces;
  for (int k = 0; k < count; ++k) zipColumns(columns[k], columns[(k + 1) % count], faces);
  mesh.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) mesh.F.row(f) = faces[f].transpose();
}

// ---------------------------------------------------------------------------------------
// Closed annulus
// ---------------------------------------------------------------------------------------

// Parametric: in-plane offsets from the centroid times closed_contraction; the saddle
// z = (closed_h / 2) cos(2 phi) with phi the open point's ellipse parameter.
Eigen::MatrixXd closedEllipseRing(const ValveParameters& p, const Ring& ring) {
  Eigen::MatrixXd closed(ring.open.rows(), 3);
  for (int k = 0; k < ring.open.rows(); ++k) {
    const Eigen::Vector3d q = ring.open.row(k).transpose();
    const double phi =
        std::atan2(q.y() / (0.5 * p.cc_diameter_mm), q.x() / (0.5 * p.ap_diameter_mm));
    closed(k, 0) = ring.frame.centre.x() + p.closed_contraction * (q.x() - ring.frame.centre.x());
    closed(k, 1) = ring.frame.centre.y() + p.closed_contraction * (q.y() - ring.frame.centre.y());
    closed(k, 2) = 0.5 * p.closed_saddle_height_mm * std::cos(2.0 * phi);
  }
  return closed;
}

// User polyline: in-plane offsets times closed_contraction, out-of-plane offsets times the
// closed/open saddle-height ratio of the parameters.
Eigen::MatrixXd closedPolylineRing(const ValveParameters& p, const Ring& ring) {
  const double ratio =
      p.saddle_height_mm > 0.0 ? p.closed_saddle_height_mm / p.saddle_height_mm : 1.0;
  const RingFrame& f = ring.frame;
  Eigen::MatrixXd closed(ring.open.rows(), 3);
  for (int k = 0; k < ring.open.rows(); ++k) {
    const Eigen::Vector3d d = ring.open.row(k).transpose() - f.centre;
    const double height = f.n.dot(d);
    const Eigen::Vector3d in_plane = d - height * f.n;
    closed.row(k) = (f.centre + p.closed_contraction * in_plane + ratio * height * f.n).transpose();
  }
  return closed;
}

}  // namespace

ParametricValve makeParametricValve(const ValveParameters& parameters) {
  validateParameters(parameters);
  const bool parametric = !parameters.annulus_polyline.has_value();
  const AnnulusCurve curve =
      parametric ? ellipseCurve(parameters) : polylineCurve(*parameters.annulus_polyline);
  const Ring ring = buildRing(parameters, curve, parametric);

  ParametricValve valve;
  valve.valve_case.name = "parametric-mitral";
  valve.valve_case.mesh.leaflet_names = {"anterior", "posterior"};
  buildMesh(ring, parameters.target_edge_mm, valve);
  valve.valve_case.annulus_closed =
      parametric ? closedEllipseRing(parameters, ring) : closedPolylineRing(parameters, ring);
  return valve;
}

}  // namespace chordfit
