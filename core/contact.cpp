#include "core/contact.h"

#include <algorithm>
#include <cmath>

#include "core/mesh_topology.h"

namespace chordfit {
namespace {

using Vec3 = Eigen::Vector3d;
using CMap3 = Eigen::Map<const Eigen::Vector3d>;

inline int cellOf(double coordinate, double origin, double inv_cell, int count) {
  return std::clamp(static_cast<int>((coordinate - origin) * inv_cell), 0, count - 1);
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
  for (int e = 0; e < E.rows(); ++e)
    mean_edge += (V_rest.row(E(e, 0)) - V_rest.row(E(e, 1))).norm();
  mean_edge = E.rows() > 0 ? mean_edge / E.rows() : 1.0;
  // Cells of about half the list radius: a triangle's inflated box then scans little more
  // than its own volume.
  min_cell_size_ =
      std::max(mean_edge, 0.5 * (options_.thickness_mm + options_.margin_mm + options_.skin_mm));
  if (!(min_cell_size_ > 0.0)) min_cell_size_ = 1.0;
  sorted_.assign(n, 0);
  cell_.assign(n, 0);
  sorted_x_.assign(3 * static_cast<size_t>(n), 0.0);
  sorted_rest_.assign(3 * static_cast<size_t>(n), 0.0);
}

namespace {

// Fewer items than this are not worth a barrier: handled as one part on the calling thread.
constexpr int kMinItemsToSplit = 512;

// Runs task(part, begin, end) over [0, count) cut into one contiguous part per thread of
// `team` (all of it as part 0 without one, or when count is small), with `parts` at least
// that many scratch parts. Returns how many parts ran: parts[0 .. n) hold the results.
template <class Part, class Task>
int inParts(SweepTeam* team, int count, std::vector<Part>& parts, Task task) {
  if (count < kMinItemsToSplit) team = nullptr;
  const int used = team ? team->threads() : 1;
  if (static_cast<int>(parts.size()) < used) parts.resize(used);
  auto run = [&](int part) {
    int begin, end;
    partRange(count, used, part, begin, end);
    task(parts[part], begin, end);
  };
  if (team)
    team->run(run);
  else
    run(0);
  return used;
}

}  // namespace

void ContactDetector::buildCandidates(const double* x, const double* w, SweepTeam* team) {
  ++rebuilds_;
  candidates_.clear();
  candidate_distance_.clear();
  const int n = static_cast<int>(sorted_.size());
  x_built_.assign(x, x + 3 * static_cast<size_t>(n));

  // Grid over the bounding box; cells at least min_cell_size_ and at most ~8 #V + 64 of them
  // (a far-flung vertex only coarsens the grid, it cannot blow up memory).
  Vec3 lo = CMap3(x), hi = CMap3(x);
  for (int i = 1; i < n; ++i) {
    lo = lo.cwiseMin(CMap3(x + 3 * i));
    hi = hi.cwiseMax(CMap3(x + 3 * i));
  }
  const Vec3 extent = (hi - lo).cwiseMax(1e-9);
  double cell = min_cell_size_;
  const double max_cells = 8.0 * n + 64.0;
  const double volume_cells = (extent / cell).array().ceil().prod();
  if (!(volume_cells <= max_cells)) cell *= std::cbrt(volume_cells / max_cells) * 1.01;
  if (!std::isfinite(cell)) return;  // non-finite positions: the simulator reports them
  const double inv_cell = 1.0 / cell;
  int* dims = dims_;
  for (int d = 0; d < 3; ++d)
    dims[d] = std::max(1, static_cast<int>(std::ceil(extent(d) * inv_cell)));
  const long num_cells = static_cast<long>(dims[0]) * dims[1] * dims[2];
  grid_lo_ = lo;
  inv_cell_ = inv_cell;

  // Counting sort by cell id = ix + dims0 (iy + dims1 iz): rows along x are contiguous.
  cell_start_.assign(num_cells + 1, 0);
  for (int i = 0; i < n; ++i) {
    const int ix = cellOf(x[3 * i], lo(0), inv_cell, dims[0]);
    const int iy = cellOf(x[3 * i + 1], lo(1), inv_cell, dims[1]);
    const int iz = cellOf(x[3 * i + 2], lo(2), inv_cell, dims[2]);
    cell_[i] = ix + dims[0] * (iy + dims[1] * iz);
    ++cell_start_[cell_[i] + 1];
  }
  for (long c = 0; c < num_cells; ++c) cell_start_[c + 1] += cell_start_[c];
  {
    std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (int i = 0; i < n; ++i) {  // vertices of a cell end up in index order
      const int slot = fill[cell_[i]]++;
      sorted_[slot] = i;
      for (int d = 0; d < 3; ++d) {
        sorted_x_[3 * slot + d] = x[3 * i + d];
        sorted_rest_[3 * slot + d] = rest_[3 * i + d];
      }
    }
  }

  // The triangles in parts, each part's candidates in triangle order: concatenated, the list
  // is the one a single pass makes.
  const int used =
      inParts(team, static_cast<int>(F_.rows()), parts_,
              [&](Part& part, int begin, int end) { candidatesOf(begin, end, x, w, part); });
  for (int p = 0; p < used; ++p) {
    const Part& part = parts_[p];
    candidates_.insert(candidates_.end(), part.candidates.begin(), part.candidates.end());
    candidate_distance_.insert(candidate_distance_.end(), part.distance.begin(),
                               part.distance.end());
  }
}

void ContactDetector::candidatesOf(int f_begin, int f_end, const double* x, const double* w,
                                   Part& part) const {
  part.candidates.clear();
  part.distance.clear();
  const Vec3& lo = grid_lo_;
  const double inv_cell = inv_cell_;
  const int* dims = dims_;
  const double reach = options_.thickness_mm + options_.margin_mm + options_.skin_mm;
  const double exclusion2 = options_.exclusion_radius_mm * options_.exclusion_radius_mm;
  for (int f = f_begin; f < f_end; ++f) {
    const int ia = F_(f, 0), ib = F_(f, 1), ic = F_(f, 2);
    const CMap3 a(x + 3 * ia), b(x + 3 * ib), c(x + 3 * ic);
    const bool triangle_fixed = w[ia] == 0.0 && w[ib] == 0.0 && w[ic] == 0.0;
    // Bounding sphere (centroid, radius) for a cheap first distance test; the box picks the
    // grid cells to scan.
    const Vec3 centroid = (a + b + c) / 3.0;
    const double sphere =
        std::sqrt(std::max({(a - centroid).squaredNorm(), (b - centroid).squaredNorm(),
                            (c - centroid).squaredNorm()})) +
        reach;
    const double sphere2 = sphere * sphere;
    const Vec3 blo = a.cwiseMin(b).cwiseMin(c) - Vec3::Constant(reach);
    const Vec3 bhi = a.cwiseMax(b).cwiseMax(c) + Vec3::Constant(reach);
    int clo[3], chi[3];
    for (int d = 0; d < 3; ++d) {
      clo[d] = cellOf(blo(d), lo(d), inv_cell, dims[d]);
      chi[d] = cellOf(bhi(d), lo(d), inv_cell, dims[d]);
    }
    const double *ra = &rest_[3 * ia], *rb = &rest_[3 * ib], *rc = &rest_[3 * ic];
    std::vector<int>& near = part.near;
    std::vector<std::pair<int, double>>& hits = part.hits;
    hits.clear();
    for (int iz = clo[2]; iz <= chi[2]; ++iz)
      for (int iy = clo[1]; iy <= chi[1]; ++iy) {
        const long row = static_cast<long>(dims[0]) * (iy + static_cast<long>(dims[1]) * iz);
        const int begin = cell_start_[row + clo[0]], end = cell_start_[row + chi[0] + 1];
        // First pass, branch-free (the branchy version mispredicted on most vertices): keep
        // the row's vertices inside the bounding sphere and not excluded, i.e. at least the
        // exclusion radius from each of the triangle's vertices in the rest state. Most
        // vertices near a triangle are its own sheet's neighbours and fail the second test.
        if (static_cast<int>(near.size()) < end - begin) near.resize(end - begin);
        int count = 0;
        for (int e = begin; e < end; ++e) {
          const double* xp = &sorted_x_[3 * e];
          const double dx = xp[0] - centroid(0), dy = xp[1] - centroid(1), dz = xp[2] - centroid(2);
          const double* rp = &sorted_rest_[3 * e];
          const double ax = rp[0] - ra[0], ay = rp[1] - ra[1], az = rp[2] - ra[2];
          const double bx = rp[0] - rb[0], by = rp[1] - rb[1], bz = rp[2] - rb[2];
          const double cx = rp[0] - rc[0], cy = rp[1] - rc[1], cz = rp[2] - rc[2];
          near[count] = e;
          count += (dx * dx + dy * dy + dz * dz <= sphere2) &
                   (ax * ax + ay * ay + az * az >= exclusion2) &
                   (bx * bx + by * by + bz * bz >= exclusion2) &
                   (cx * cx + cy * cy + cz * cz >= exclusion2);
        }
        for (int k = 0; k < count; ++k) {
          const int e = near[k];
          const CMap3 xpm(&sorted_x_[3 * e]);
          const int p = sorted_[e];
          if (triangle_fixed && w[p] == 0.0) continue;
          if (p == ia || p == ib || p == ic) continue;  // only reached with exclusion radius 0
          double ba, bb, bc;
          closestPointOnTriangle(xpm, a, b, c, ba, bb, bc);
          const double dist2 = (xpm - (ba * a + bb * b + bc * c)).squaredNorm();
          if (dist2 >= reach * reach) continue;
          hits.emplace_back(p, std::sqrt(dist2));
        }
      }
    // Rows are visited in grid order; this triangle's vertices go in by index.
    std::sort(hits.begin(), hits.end());
    for (const auto& [p, dist] : hits) {
      part.candidates.emplace_back(f, p);
      part.distance.push_back(dist);
    }
  }
}

void ContactDetector::detect(const double* x_start, const double* x_pred, const double* w,
                             std::vector<ContactConstraint>& out, SweepTeam* team) {
  out.clear();
  const int n = static_cast<int>(sorted_.size());
  if (n == 0) return;
  // Rebuild the Verlet list when a vertex moved more than skin / 2 since the last build.
  bool rebuild = x_built_.size() != 3 * static_cast<size_t>(n);
  moved_.resize(n);
  if (!rebuild) {
    double max_moved = 0.0;
    for (int i = 0; i < n; ++i) {
      moved_[i] = (CMap3(x_pred + 3 * i) - CMap3(&x_built_[3 * i])).norm();
      max_moved = std::max(max_moved, moved_[i]);
    }
    rebuild = !(max_moved <= 0.5 * options_.skin_mm);
  }
  if (rebuild) {
    buildCandidates(x_pred, w, team);
    std::fill(moved_.begin(), moved_.end(), 0.0);
  }
  // The candidates in parts; concatenated, the constraints are those of a single pass, in
  // the same order.
  const int used = inParts(
      team, static_cast<int>(candidates_.size()), parts_,
      [&](Part& part, int begin, int end) { filterCandidates(begin, end, x_start, x_pred, part); });
  for (int p = 0; p < used; ++p)
    out.insert(out.end(), parts_[p].contacts.begin(), parts_[p].contacts.end());
}

void ContactDetector::filterCandidates(size_t e_begin, size_t e_end, const double* x_start,
                                       const double* x_pred, Part& part) const {
  part.contacts.clear();
  // Constraints: every pair within thickness + margin. (Keeping only the triangle "under" a
  // vertex and adding edge-region pairs once violated cut the count ~5x but made pairs switch
  // in and out at rest, and the 2000-vertex closure never settled.)
  const double reach = options_.thickness_mm + options_.margin_mm;
  const double reach2 = reach * reach;
  // A pair is skipped only when its distance bound clears reach by far more than rounding,
  // so the constraints are exactly those an exhaustive filter finds.
  const double skip_above = reach + 1e-9;
  int face = -1, ia = 0, ib = 0, ic = 0;
  double face_moved = 0.0;
  bool have_sphere = false;
  Vec3 centroid = Vec3::Zero();
  double sphere2 = 0.0;
  for (size_t e = e_begin; e < e_end; ++e) {
    const auto [f, p] = candidates_[e];
    if (f != face) {  // candidates are grouped by triangle
      face = f;
      ia = F_(f, 0), ib = F_(f, 1), ic = F_(f, 2);
      face_moved = std::max({moved_[ia], moved_[ib], moved_[ic]});
      have_sphere = false;
    }
    if (candidate_distance_[e] - moved_[p] - face_moved > skip_above) continue;
    const CMap3 a(x_pred + 3 * ia), b(x_pred + 3 * ib), c(x_pred + 3 * ic);
    if (!have_sphere) {  // the triangle's bounding sphere, once
      have_sphere = true;
      centroid = (a + b + c) / 3.0;
      const double radius =
          std::sqrt(std::max({(a - centroid).squaredNorm(), (b - centroid).squaredNorm(),
                              (c - centroid).squaredNorm()}));
      sphere2 = (radius + reach) * (radius + reach);
    }
    const CMap3 xp(x_pred + 3 * p);
    if ((xp - centroid).squaredNorm() > sphere2) continue;
    double ba, bb, bc;
    closestPointOnTriangle(xp, a, b, c, ba, bb, bc);
    if ((xp - (ba * a + bb * b + bc * c)).squaredNorm() >= reach2) continue;
    part.contacts.push_back(
        contactConstraint(p, ia, ib, ic, x_start, x_pred, options_.thickness_mm));
  }
}

ContactConstraint contactConstraint(int p, int a, int b, int c, const double* x_start,
                                    const double* x_pred, double thickness) {
  // Side: of the start-of-step plane of the triangle (free of crossings unless a later projection
  // pulled a vertex through within one step, contact.h); if the
  // vertex lies in that plane, of the predicted one.
  const CMap3 a0(x_start + 3 * a), b0(x_start + 3 * b), c0(x_start + 3 * c);
  double side = (b0 - a0).cross(c0 - a0).dot(CMap3(x_start + 3 * p) - a0);
  if (side == 0.0) {
    const CMap3 xa(x_pred + 3 * a), xb(x_pred + 3 * b), xc(x_pred + 3 * c);
    side = (xb - xa).cross(xc - xa).dot(CMap3(x_pred + 3 * p) - xa);
  }
  ContactConstraint k;
  k.p = p, k.a = a, k.b = b, k.c = c;
  k.side = side >= 0.0 ? 1.0 : -1.0;
  k.thickness = thickness;
  return k;
}

}  // namespace chordfit
