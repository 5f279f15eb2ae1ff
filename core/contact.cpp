#include "core/contact.h"

#include <algorithm>
#include <cmath>

#include "core/mesh_topology.h"

namespace chordfit {
namespace {

using Vec3 = Eigen::Vector3d;
using CMap3 = Eigen::Map<const Eigen::Vector3d>;

inline int hashCell(int ix, int iy, int iz, int buckets) {
  // Teschner et al. 2003 hash primes.
  const unsigned h = (static_cast<unsigned>(ix) * 92837111u) ^
                     (static_cast<unsigned>(iy) * 689287499u) ^
                     (static_cast<unsigned>(iz) * 283923481u);
  return static_cast<int>(h % static_cast<unsigned>(buckets));
}

inline int cellOf(double coordinate, double inv_cell) {
  return static_cast<int>(std::floor(coordinate * inv_cell));
}

}  // namespace

ContactDetector::ContactDetector(const Eigen::MatrixXd& V_rest, const Eigen::MatrixXi& F,
                                 const ContactOptions& options)
    : options_(options), F_(F) {
  const int n = static_cast<int>(V_rest.rows());
  rest_.resize(3 * static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) rest_[3 * i + d] = V_rest(i, d);
  const Eigen::MatrixXi E = uniqueEdges(F);
  double mean_edge = 0.0;
  for (int e = 0; e < E.rows(); ++e) mean_edge += (V_rest.row(E(e, 0)) - V_rest.row(E(e, 1))).norm();
  mean_edge = E.rows() > 0 ? mean_edge / E.rows() : 1.0;
  cell_size_ = std::max(mean_edge, options_.thickness_mm + options_.margin_mm + options_.skin_mm);
  if (!(cell_size_ > 0.0)) cell_size_ = 1.0;
  bucket_start_.assign(2 * static_cast<size_t>(std::max(n, 1)) + 1, 0);
  bucket_entries_.assign(n, 0);
  cell_.assign(3 * static_cast<size_t>(n), 0);
}

bool ContactDetector::excluded(int p, int a, int b, int c) const {
  if (p == a || p == b || p == c) return true;
  const double r2 = options_.exclusion_radius_mm * options_.exclusion_radius_mm;
  const CMap3 xp(&rest_[3 * p]);
  for (int v : {a, b, c})
    if ((CMap3(&rest_[3 * v]) - xp).squaredNorm() < r2) return true;
  return false;
}

void ContactDetector::buildCandidates(const double* x, const double* w) {
  ++rebuilds_;
  candidates_.clear();
  const int n = static_cast<int>(bucket_entries_.size());
  x_built_.assign(x, x + 3 * static_cast<size_t>(n));
  const int buckets = static_cast<int>(bucket_start_.size()) - 1;
  const double inv_cell = 1.0 / cell_size_;

  // Counting sort of the vertices into hash buckets.
  std::fill(bucket_start_.begin(), bucket_start_.end(), 0);
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) cell_[3 * i + d] = cellOf(x[3 * i + d], inv_cell);
    ++bucket_start_[hashCell(cell_[3 * i], cell_[3 * i + 1], cell_[3 * i + 2], buckets)];
  }
  for (int b = 0, sum = 0; b <= buckets; ++b) {
    sum += bucket_start_[b];
    bucket_start_[b] = sum;  // end of bucket b; the fill below moves it to its start
  }
  for (int i = n - 1; i >= 0; --i) {
    const int b = hashCell(cell_[3 * i], cell_[3 * i + 1], cell_[3 * i + 2], buckets);
    bucket_entries_[--bucket_start_[b]] = i;  // vertices of a bucket end up in index order
  }

  const double reach = options_.thickness_mm + options_.margin_mm + options_.skin_mm;
  for (int f = 0; f < F_.rows(); ++f) {
    const int ia = F_(f, 0), ib = F_(f, 1), ic = F_(f, 2);
    const CMap3 a(x + 3 * ia), b(x + 3 * ib), c(x + 3 * ic);
    const bool triangle_fixed = w[ia] == 0.0 && w[ib] == 0.0 && w[ic] == 0.0;
    const Vec3 lo = a.cwiseMin(b).cwiseMin(c) - Vec3::Constant(reach);
    const Vec3 hi = a.cwiseMax(b).cwiseMax(c) + Vec3::Constant(reach);
    int clo[3], chi[3];
    for (int d = 0; d < 3; ++d) {
      clo[d] = cellOf(lo(d), inv_cell);
      chi[d] = cellOf(hi(d), inv_cell);
    }
    const size_t first = candidates_.size();
    for (int ix = clo[0]; ix <= chi[0]; ++ix)
      for (int iy = clo[1]; iy <= chi[1]; ++iy)
        for (int iz = clo[2]; iz <= chi[2]; ++iz) {
          const int bucket = hashCell(ix, iy, iz, buckets);
          for (int e = bucket_start_[bucket]; e < bucket_start_[bucket + 1]; ++e) {
            const int p = bucket_entries_[e];
            if (cell_[3 * p] != ix || cell_[3 * p + 1] != iy || cell_[3 * p + 2] != iz) continue;
            if (triangle_fixed && w[p] == 0.0) continue;
            const CMap3 xp(x + 3 * p);
            if ((xp.array() < lo.array()).any() || (xp.array() > hi.array()).any()) continue;
            if (excluded(p, ia, ib, ic)) continue;
            double ba, bb, bc;
            closestPointOnTriangle(xp, a, b, c, ba, bb, bc);
            if ((xp - (ba * a + bb * b + bc * c)).squaredNorm() >= reach * reach) continue;
            candidates_.emplace_back(f, p);
          }
        }
    // Cells are visited in grid order; sort this triangle's vertices by index.
    std::sort(candidates_.begin() + first, candidates_.end());
  }
}

void ContactDetector::detect(const double* x_start, const double* x_pred, const double* w,
                             std::vector<ContactConstraint>& out) {
  out.clear();
  const int n = static_cast<int>(bucket_entries_.size());
  if (n == 0) return;
  // Rebuild the Verlet list when a vertex moved more than skin / 2 since the last build.
  bool rebuild = x_built_.size() != 3 * static_cast<size_t>(n);
  if (!rebuild) {
    const double limit2 = 0.25 * options_.skin_mm * options_.skin_mm;
    for (int i = 0; i < n && !rebuild; ++i)
      rebuild = (CMap3(x_pred + 3 * i) - CMap3(&x_built_[3 * i])).squaredNorm() > limit2;
  }
  if (rebuild) buildCandidates(x_pred, w);

  const double reach = options_.thickness_mm + options_.margin_mm;
  const double reach2 = reach * reach;
  for (size_t pair = 0; pair < candidates_.size(); ++pair) {
    const auto [f, p] = candidates_[pair];
    const int ia = F_(f, 0), ib = F_(f, 1), ic = F_(f, 2);
    const CMap3 a(x_pred + 3 * ia), b(x_pred + 3 * ib), c(x_pred + 3 * ic);
    const CMap3 xp(x_pred + 3 * p);
    double ba, bb, bc;
    closestPointOnTriangle(xp, a, b, c, ba, bb, bc);
    if ((xp - (ba * a + bb * b + bc * c)).squaredNorm() >= reach2) continue;
    // Side: of the start-of-step plane of the triangle (non-penetrating by induction); if the
    // vertex lies in that plane, of the predicted one.
    const CMap3 a0(x_start + 3 * ia), b0(x_start + 3 * ib), c0(x_start + 3 * ic);
    double side = (b0 - a0).cross(c0 - a0).dot(CMap3(x_start + 3 * p) - a0);
    if (side == 0.0) side = (b - a).cross(c - a).dot(xp - a);
    ContactConstraint k;
    k.p = p, k.a = ia, k.b = ib, k.c = ic;
    k.side = side >= 0.0 ? 1.0 : -1.0;
    k.thickness = options_.thickness_mm;
    out.push_back(k);
  }
}

}  // namespace chordfit
