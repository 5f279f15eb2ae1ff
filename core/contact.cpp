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
  cell_size_ = std::max(mean_edge, options_.thickness_mm + options_.margin_mm);
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

void ContactDetector::detect(const double* x_start, const double* x_pred, const double* w,
                             std::vector<ContactConstraint>& out) {
  out.clear();
  const int n = static_cast<int>(bucket_entries_.size());
  if (n == 0) return;
  const int buckets = static_cast<int>(bucket_start_.size()) - 1;
  const double inv_cell = 1.0 / cell_size_;

  // Counting sort of the vertices (predicted positions) into hash buckets.
  std::fill(bucket_start_.begin(), bucket_start_.end(), 0);
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) cell_[3 * i + d] = cellOf(x_pred[3 * i + d], inv_cell);
    ++bucket_start_[hashCell(cell_[3 * i], cell_[3 * i + 1], cell_[3 * i + 2], buckets)];
  }
  for (int b = 0, sum = 0; b <= buckets; ++b) {
    sum += bucket_start_[b];
    bucket_start_[b] = sum;  // end of bucket b (exclusive prefix after the fill below)
  }
  for (int i = n - 1; i >= 0; --i) {
    const int b = hashCell(cell_[3 * i], cell_[3 * i + 1], cell_[3 * i + 2], buckets);
    bucket_entries_[--bucket_start_[b]] = i;  // vertices of a bucket end up in index order
  }

  const double reach = options_.thickness_mm + options_.margin_mm;
  const double reach2 = reach * reach;
  for (int f = 0; f < F_.rows(); ++f) {
    const int ia = F_(f, 0), ib = F_(f, 1), ic = F_(f, 2);
    const CMap3 a(x_pred + 3 * ia), b(x_pred + 3 * ib), c(x_pred + 3 * ic);
    const bool triangle_fixed = w[ia] == 0.0 && w[ib] == 0.0 && w[ic] == 0.0;
    Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    lo -= Vec3::Constant(reach);
    hi += Vec3::Constant(reach);
    int clo[3], chi[3];
    for (int d = 0; d < 3; ++d) {
      clo[d] = cellOf(lo(d), inv_cell);
      chi[d] = cellOf(hi(d), inv_cell);
    }
    const CMap3 a0(x_start + 3 * ia), b0(x_start + 3 * ib), c0(x_start + 3 * ic);
    Vec3 normal_pred = (b - a).cross(c - a);
    const double npl = normal_pred.norm();
    if (npl < 1e-14) continue;  // degenerate triangle: no usable normal
    normal_pred /= npl;
    const Vec3 normal_start = (b0 - a0).cross(c0 - a0);

    for (int ix = clo[0]; ix <= chi[0]; ++ix)
      for (int iy = clo[1]; iy <= chi[1]; ++iy)
        for (int iz = clo[2]; iz <= chi[2]; ++iz) {
          const int bucket = hashCell(ix, iy, iz, buckets);
          for (int e = bucket_start_[bucket]; e < bucket_start_[bucket + 1]; ++e) {
            const int p = bucket_entries_[e];
            if (cell_[3 * p] != ix || cell_[3 * p + 1] != iy || cell_[3 * p + 2] != iz) continue;
            if (triangle_fixed && w[p] == 0.0) continue;
            const CMap3 xp(x_pred + 3 * p);
            if ((xp.array() < lo.array()).any() || (xp.array() > hi.array()).any()) continue;
            if (excluded(p, ia, ib, ic)) continue;
            double ba, bb, bc;
            const int region = closestPointOnTriangle(xp, a, b, c, ba, bb, bc);
            const Vec3 q = ba * a + bb * b + bc * c;
            const Vec3 d = xp - q;
            const double dist2 = d.squaredNorm();
            if (dist2 >= reach2) continue;
            Vec3 nrm;
            if (region == 0) {
              // Side of the start-of-step plane of T (non-penetrating by induction).
              const double side_start = normal_start.dot(CMap3(x_start + 3 * p) - a0);
              const double side = side_start != 0.0 ? side_start : normal_pred.dot(d);
              nrm = side >= 0.0 ? normal_pred : Vec3(-normal_pred);
            } else {
              const double dist = std::sqrt(dist2);
              if (dist < 1e-12) continue;
              nrm = d / dist;
            }
            ContactConstraint k;
            k.p = p, k.a = ia, k.b = ib, k.c = ic;
            k.ba = ba, k.bb = bb, k.bc = bc;
            k.n[0] = nrm(0), k.n[1] = nrm(1), k.n[2] = nrm(2);
            k.thickness = options_.thickness_mm;
            out.push_back(k);
          }
        }
  }
}

}  // namespace chordfit
