#include "core/orifice_coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace chordfit {
namespace {

using Vec2 = Eigen::Vector2d;

// (b - a) x (q - a): > 0 when q lies left of the directed line a -> b.
double cross(const Vec2& a, const Vec2& b, const Vec2& q) { return cross2d(b - a, q - a); }

// Squared distance from q to the segment a-b.
double squaredDistanceToSegment(const Vec2& a, const Vec2& b, const Vec2& q) {
  const Vec2 ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((q - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (q - a - t * ab).squaredNorm();
}

}  // namespace

double OrificeCoverage::coverage() const {
  if (samples == 0) return std::numeric_limits<double>::quiet_NaN();
  return 1.0 - open_area_mm2 / orifice_area_mm2;
}

OrificeCoverage orificeCoverage(const Eigen::MatrixXd& ring, const Eigen::MatrixXd& V,
                                const Eigen::MatrixXi& F, const AnnulusFrame& frame, double grid_mm,
                                double tissue_radius_mm) {
  OrificeCoverage result;
  const double r = std::isfinite(tissue_radius_mm) ? std::max(tissue_radius_mm, 0.0) : 0.0;
  const double r2 = r * r;
  result.tissue_radius_mm = r;
  if (ring.rows() < 3 || !ring.allFinite() || !(grid_mm > 0.0)) return result;
  auto project = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = p - frame.plane.centre;
    return Vec2(frame.a.dot(d), frame.l.dot(d));
  };
  std::vector<Vec2> polygon;
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (Eigen::Index i = 0; i < ring.rows(); ++i) {
    polygon.push_back(project(ring.row(i).transpose()));
    lo = lo.cwiseMin(polygon.back());
    hi = hi.cwiseMax(polygon.back());
  }
  // Samples at lo + (i, j) grid_mm inside the ring's bounding box; a ring in other units
  // (metres, microns) or a wild vertex coarsens the grid to at most kMaxSamples points rather
  // than allocating without bound.
  constexpr double kMaxSamples = 4e6;
  const double box = (hi.x() - lo.x() + grid_mm) * (hi.y() - lo.y() + grid_mm);
  if (box / (grid_mm * grid_mm) > kMaxSamples) grid_mm = std::sqrt(box / kMaxSamples);
  const int nx = static_cast<int>(std::floor((hi.x() - lo.x()) / grid_mm)) + 1;
  const int ny = static_cast<int>(std::floor((hi.y() - lo.y()) / grid_mm)) + 1;
  auto sample = [&](int i, int j) { return Vec2(lo.x() + i * grid_mm, lo.y() + j * grid_mm); };

  // Inside the ring (even-odd rule), one scan line per grid row: a sample is inside when an
  // odd number of ring edges cross its row to its right.
  std::vector<char> inside(static_cast<size_t>(nx) * ny, 0);
  std::vector<double> crossings;
  for (int j = 0; j < ny; ++j) {
    const double y = lo.y() + j * grid_mm;
    crossings.clear();
    for (size_t k = 0, m = polygon.size() - 1; k < polygon.size(); m = k++) {
      const Vec2 &p = polygon[k], &q = polygon[m];
      if ((p.y() > y) != (q.y() > y))
        crossings.push_back(q.x() + (y - q.y()) * (p.x() - q.x()) / (p.y() - q.y()));
    }
    std::sort(crossings.begin(), crossings.end());
    for (int i = 0; i < nx; ++i) {
      const double x = lo.x() + i * grid_mm;
      const auto right = crossings.end() - std::upper_bound(crossings.begin(), crossings.end(), x);
      inside[static_cast<size_t>(j) * nx + i] = right % 2 == 1;
    }
  }

  // Covered: each triangle marks the samples of its bounding box (grown by r) that lie in it
  // (edges included, either winding) or within r of one of its edges.
  std::vector<char> covered(inside.size(), 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec2 t0 = project(V.row(F(f, 0)).transpose()), t1 = project(V.row(F(f, 1)).transpose()),
               t2 = project(V.row(F(f, 2)).transpose());
    const Vec2 tlo = t0.cwiseMin(t1).cwiseMin(t2) - Vec2::Constant(r),
               thi = t0.cwiseMax(t1).cwiseMax(t2) + Vec2::Constant(r);
    if (!tlo.allFinite() || !thi.allFinite()) continue;
    const int i0 = std::max(0, static_cast<int>(std::ceil((tlo.x() - lo.x()) / grid_mm)));
    const int i1 = std::min(nx - 1, static_cast<int>(std::floor((thi.x() - lo.x()) / grid_mm)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((tlo.y() - lo.y()) / grid_mm)));
    const int j1 = std::min(ny - 1, static_cast<int>(std::floor((thi.y() - lo.y()) / grid_mm)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const size_t cell = static_cast<size_t>(j) * nx + i;
        if (!inside[cell] || covered[cell]) continue;
        const Vec2 q = sample(i, j);
        const double d0 = cross(t0, t1, q), d1 = cross(t1, t2, q), d2 = cross(t2, t0, q);
        if ((d0 >= 0 && d1 >= 0 && d2 >= 0) || (d0 <= 0 && d1 <= 0 && d2 <= 0) ||
            (r > 0.0 && (squaredDistanceToSegment(t0, t1, q) <= r2 ||
                         squaredDistanceToSegment(t1, t2, q) <= r2 ||
                         squaredDistanceToSegment(t2, t0, q) <= r2)))
          covered[cell] = 1;
      }
  }

  int hits = 0;
  for (size_t cell = 0; cell < inside.size(); ++cell) {
    result.samples += inside[cell];
    hits += inside[cell] && covered[cell];
  }
  const double cell_area = grid_mm * grid_mm;
  result.orifice_area_mm2 = result.samples * cell_area;
  result.open_area_mm2 = (result.samples - hits) * cell_area;
  return result;
}

}  // namespace chordfit
