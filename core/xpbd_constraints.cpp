#include "core/xpbd_constraints.h"

#include <algorithm>
#include <cmath>

namespace chordfit {
namespace {

using Vec3 = Eigen::Vector3d;
using Map3 = Eigen::Map<Eigen::Vector3d>;
using CMap3 = Eigen::Map<const Eigen::Vector3d>;

inline Map3 at(double* x, int i) { return Map3(x + 3 * static_cast<long>(i)); }

}  // namespace

namespace {

// acc (optional): receives grad_i C * lambda for every vertex of every constraint, with the
// total lambda after the update (the constraint impulse, used to warm-start the next step).
inline void accumulate(double* acc, int i, const Vec3& g, double lambda) {
  Map3(acc + 3 * static_cast<long>(i)) += lambda * g;
}

template <bool kAcc>
void distanceSweep(const DistanceConstraint* constraints, int n, double inv_dt2, double* x,
                   const double* w, double* lambda, double* acc) {
  for (int c = 0; c < n; ++c) {
    const DistanceConstraint& k = constraints[c];
    const double wsum = w[k.i] + w[k.j];
    if (wsum == 0.0) continue;
    Map3 xi = at(x, k.i), xj = at(x, k.j);
    const Vec3 d = xi - xj;
    const double len = d.norm();
    if (len < 1e-12) continue;
    const double alpha = k.compliance * inv_dt2;
    // grad_i C = d/|d|, grad_j C = -d/|d|, |grad|^2 = 1.
    const double dl = (-(len - k.rest) - alpha * lambda[c]) / (wsum + alpha);
    lambda[c] += dl;
    const Vec3 n_ij = d / len;
    xi += (w[k.i] * dl) * n_ij;
    xj -= (w[k.j] * dl) * n_ij;
    if (kAcc) {
      accumulate(acc, k.i, n_ij, lambda[c]);
      accumulate(acc, k.j, -n_ij, lambda[c]);
    }
  }
}

}  // namespace

void projectDistances(const DistanceConstraint* constraints, int count, double inv_dt2, double* x,
                      const double* w, double* lambda, double* acc) {
  if (acc)
    distanceSweep<true>(constraints, count, inv_dt2, x, w, lambda, acc);
  else
    distanceSweep<false>(constraints, count, inv_dt2, x, w, lambda, acc);
}

namespace {

// atan2 to double precision (max error ~4e-16 rad against std::atan2 on random inputs): range
// reduction to |t| <= tan(pi/8) and the Cephes atan rational approximation (Moshier,
// "Methods and programs for mathematical functions", 1989). Inlined and branch-light it is
// several times faster than the libm call that dominated the bending projection.
inline double atan2Fast(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double hi = std::max(ax, ay), lo = std::min(ax, ay);
  if (hi == 0.0) return 0.0;
  double t = lo / hi, base = 0.0;
  if (t > 0.41421356237309503) {  // tan(pi/8)
    t = (t - 1.0) / (t + 1.0);
    base = M_PI / 4;
  }
  const double z = t * t;
  const double p = (((-8.750608600031904122785e-1 * z - 1.615753718733365076637e1) * z -
                     7.500855792314704667340e1) *
                        z -
                    1.228866684490136173410e2) *
                       z -
                   6.485021904942025371773e1;
  const double q = ((((z + 2.485846490142306297962e1) * z + 1.650270098316988542046e2) * z +
                     4.328810604912902668951e2) *
                        z +
                    4.853903996359136964868e2) *
                       z +
                   1.945506571482613964425e2;
  double r = base + t + t * z * p / q;
  if (ay > ax) r = M_PI / 2 - r;
  if (x < 0.0) r = M_PI - r;
  return y < 0.0 ? -r : r;
}

template <class V>
inline double dihedralAngleImpl(const V& xi, const V& xj, const V& xk, const V& xl, Vec3* grad) {
  // Bridson et al. 2003 with x3 = xi, x4 = xj (hinge E = x4 - x3), x1 = xk, x2 = xl:
  // N1 = (x1 - x3) x (x1 - x4), N2 = (x2 - x4) x (x2 - x3) (= the faces' winding normals).
  const Vec3 e = xj - xi;
  const Vec3 ek = xk - xi, el = xl - xi;
  const Vec3 n1 = ek.cross(xk - xj);
  const Vec3 n2 = (xl - xj).cross(el);
  const double n1sq = n1.squaredNorm(), n2sq = n2.squaredNorm(), e2 = e.squaredNorm();
  if (n1sq < 1e-24 || n2sq < 1e-24 || e2 < 1e-24) {
    if (grad)
      for (int m = 0; m < 4; ++m) grad[m].setZero();
    return 0.0;
  }
  const double elen = std::sqrt(e2), inv_e = 1.0 / elen;
  // sin theta ~ (n2 x n1) . e / |e|, cos theta ~ n1 . n2 (common positive factor cancels).
  const double theta = atan2Fast(n2.cross(n1).dot(e) * inv_e, n1.dot(n2));
  if (grad) {
    const Vec3 a1 = n1 * (1.0 / n1sq), a2 = n2 * (1.0 / n2sq);
    // (x_k - x_j).e = (x_k - x_i).e - |e|^2, same for l.
    const double s1 = ek.dot(e) * inv_e, s2 = el.dot(e) * inv_e;
    grad[2] = elen * a1;
    grad[3] = elen * a2;
    grad[0] = (s1 - elen) * a1 + (s2 - elen) * a2;
    grad[1] = -s1 * a1 - s2 * a2;
  }
  return theta;
}

template <class V>
inline double triangleAreaImpl(const V& xa, const V& xb, const V& xc, Vec3* grad) {
  const Vec3 N = (xb - xa).cross(xc - xa);
  const double len = N.norm();
  if (grad) {
    if (len < 1e-24) {
      for (int m = 0; m < 3; ++m) grad[m].setZero();
    } else {
      // dA/dx_a = n x (x_c - x_b) / 2 and cyclic (n = N/|N|).
      const Vec3 nh = N / len;
      grad[0] = 0.5 * nh.cross(xc - xb);
      grad[1] = 0.5 * nh.cross(xa - xc);
      grad[2] = 0.5 * nh.cross(xb - xa);
    }
  }
  return 0.5 * len;
}

}  // namespace

double dihedralAngle(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj,
                     const Eigen::Vector3d& xk, const Eigen::Vector3d& xl, Eigen::Vector3d* grad) {
  return dihedralAngleImpl(xi, xj, xk, xl, grad);
}

double triangleArea(const Eigen::Vector3d& xa, const Eigen::Vector3d& xb, const Eigen::Vector3d& xc,
                    Eigen::Vector3d* grad) {
  return triangleAreaImpl(xa, xb, xc, grad);
}

namespace {

template <bool kAcc>
void bendingSweep(const BendingConstraint* constraints, int n, double inv_dt2, double* x,
                  const double* w, double* lambda, double* acc) {
  for (int c = 0; c < n; ++c) {
    const BendingConstraint& k = constraints[c];
    const double wi = w[k.i], wj = w[k.j], wk = w[k.k], wl = w[k.l];
    if (wi + wj + wk + wl == 0.0) continue;
    Map3 xi = at(x, k.i), xj = at(x, k.j), xk = at(x, k.k), xl = at(x, k.l);
    Vec3 g[4];
    const double theta = dihedralAngleImpl(xi, xj, xk, xl, g);
    const double denom_w = wi * g[0].squaredNorm() + wj * g[1].squaredNorm() +
                           wk * g[2].squaredNorm() + wl * g[3].squaredNorm();
    if (denom_w < 1e-24) continue;
    const double alpha = k.compliance * inv_dt2;
    double C = theta - k.rest_angle;
    // Keep C in (-pi, pi] so a fold through +-pi does not flip the restoring direction.
    if (C > M_PI) C -= 2.0 * M_PI;
    if (C < -M_PI) C += 2.0 * M_PI;
    const double dl = (-C - alpha * lambda[c]) / (denom_w + alpha);
    lambda[c] += dl;
    xi += (wi * dl) * g[0];
    xj += (wj * dl) * g[1];
    xk += (wk * dl) * g[2];
    xl += (wl * dl) * g[3];
    if (kAcc) {
      accumulate(acc, k.i, g[0], lambda[c]);
      accumulate(acc, k.j, g[1], lambda[c]);
      accumulate(acc, k.k, g[2], lambda[c]);
      accumulate(acc, k.l, g[3], lambda[c]);
    }
  }
}

// One triangle of an area constraint (or floor) at the current positions: edges and
// N = (x_b - x_a) x (x_c - x_a), so A = |N| / 2. Shared by the area and area-floor sweeps.
struct AreaTriangle {
  Vec3 eab, ebc, eca, N;
  double len = 0.0;  // |N| = 2 A
};

inline AreaTriangle areaTriangle(const AreaConstraint& k, const double* x) {
  const CMap3 xa(x + 3 * static_cast<long>(k.a)), xb(x + 3 * static_cast<long>(k.b)),
      xc(x + 3 * static_cast<long>(k.c));
  AreaTriangle t;
  t.eab = xb - xa, t.ebc = xc - xb, t.eca = xa - xc;
  t.N = t.eab.cross(-t.eca);
  t.len = t.N.norm();
  return t;
}

// grad_a A = n x (x_c - x_b) / 2 (and cyclic), n the unit normal; since n is orthogonal to
// the edges, |grad_a A|^2 = |x_c - x_b|^2 / 4. Returns sum_m w_m |grad_m A|^2.
inline double areaDenominator(const AreaConstraint& k, const AreaTriangle& t, const double* w) {
  return 0.25 * (w[k.a] * t.ebc.squaredNorm() + w[k.b] * t.eca.squaredNorm() +
                 w[k.c] * t.eab.squaredNorm());
}

// x_m += w_m dlambda grad_m A, and (kAcc) the impulse grad_m A lambda into acc.
template <bool kAcc>
inline void applyAreaCorrection(const AreaConstraint& k, const AreaTriangle& t, double dl,
                                double lambda, double* x, const double* w, double* acc) {
  const Vec3 nh = (0.5 / t.len) * t.N;
  const Vec3 g[3] = {nh.cross(t.ebc), nh.cross(t.eca), nh.cross(t.eab)};
  at(x, k.a) += (w[k.a] * dl) * g[0];
  at(x, k.b) += (w[k.b] * dl) * g[1];
  at(x, k.c) += (w[k.c] * dl) * g[2];
  if (kAcc) {
    accumulate(acc, k.a, g[0], lambda);
    accumulate(acc, k.b, g[1], lambda);
    accumulate(acc, k.c, g[2], lambda);
  }
}

template <bool kAcc>
void areaSweep(const AreaConstraint* constraints, int n, double inv_dt2, double* x, const double* w,
               double* lambda, double* acc) {
  for (int c = 0; c < n; ++c) {
    const AreaConstraint& k = constraints[c];
    if (w[k.a] + w[k.b] + w[k.c] == 0.0) continue;
    const AreaTriangle t = areaTriangle(k, x);
    if (t.len < 1e-24) continue;
    const double alpha = k.compliance * inv_dt2;
    const double dl =
        (-(0.5 * t.len - k.rest_area) - alpha * lambda[c]) / (areaDenominator(k, t, w) + alpha);
    lambda[c] += dl;
    applyAreaCorrection<kAcc>(k, t, dl, lambda[c], x, w, acc);
  }
}

template <bool kAcc>
void areaFloorSweep(const AreaConstraint* constraints, int n, double* x, const double* w,
                    double* lambda, double* acc) {
  for (int c = 0; c < n; ++c) {
    const AreaConstraint& k = constraints[c];
    if (w[k.a] + w[k.b] + w[k.c] == 0.0) continue;
    const AreaTriangle t = areaTriangle(k, x);
    if (t.len < 1e-24) continue;
    const double C = 0.5 * t.len - k.rest_area;
    if (C > 0.0 && lambda[c] == 0.0) continue;
    // Hard constraint: dlambda = -C / sum_m w_m |grad_m A|^2; a floor only pushes out.
    const double total = std::max(lambda[c] - C / areaDenominator(k, t, w), 0.0);
    const double dl = total - lambda[c];
    lambda[c] = total;
    applyAreaCorrection<kAcc>(k, t, dl, total, x, w, acc);
  }
}

template <bool kAcc>
void cordSweep(const std::vector<CordConstraint>& constraints, double inv_dt2, const double* tips,
               double* x, const double* w, double* lambda, double* acc, double max_pull) {
  const int n = static_cast<int>(constraints.size());
  for (int c = 0; c < n; ++c) {
    const CordConstraint& k = constraints[c];
    const int count = static_cast<int>(k.vertices.size());
    double denominator = 0.0;
    Vec3 xv = Vec3::Zero();
    if (count == 1) {
      denominator = w[k.vertices[0]];
      xv = at(x, k.vertices[0]);
    } else {
      for (int m = 0; m < count; ++m) {
        denominator += k.weights[m] * k.weights[m] * w[k.vertices[m]];
        xv += k.weights[m] * at(x, k.vertices[m]);
      }
    }
    if (denominator == 0.0) continue;
    const CMap3 tip(tips + 3 * static_cast<long>(k.tip));
    const Vec3 d = xv - tip;
    const double len = d.norm();
    if (len < 1e-12) continue;
    const double C = len - k.rest;
    if (C < 0.0 && lambda[c] == 0.0) continue;  // slack: k^CT = 0 (paper eq. 1)
    const double alpha = k.compliance * inv_dt2;
    double dl = (-C - alpha * lambda[c]) / (denominator + alpha);
    // The insertion moves by dl * denominator along n: at most max_pull toward the tip.
    if (max_pull > 0.0 && -dl * denominator > max_pull) dl = -max_pull / denominator;
    // A cord only pulls: accumulated lambda stays <= 0.
    const double total = std::min(lambda[c] + dl, 0.0);
    dl = total - lambda[c];
    lambda[c] = total;
    const Vec3 g = d / len;
    if (count == 1) {
      at(x, k.vertices[0]) += (w[k.vertices[0]] * dl) * g;
      if (kAcc) accumulate(acc, k.vertices[0], g, total);
      continue;
    }
    for (int m = 0; m < count; ++m) {
      at(x, k.vertices[m]) += (k.weights[m] * w[k.vertices[m]] * dl) * g;
      if (kAcc) accumulate(acc, k.vertices[m], k.weights[m] * g, total);
    }
  }
}

// Contact distance C of the point xp from k's triangle and its unit direction u (see
// ContactConstraint).
template <class P>
inline bool contactStateAt(const P& xp, const ContactConstraint& k, const double* x, double& C,
                           Vec3& u, double bary[3]) {
  const CMap3 xa(x + 3 * static_cast<long>(k.a)), xb(x + 3 * static_cast<long>(k.b)),
      xc(x + 3 * static_cast<long>(k.c));
  const int region = closestPointOnTriangle(xp, xa, xb, xc, bary[0], bary[1], bary[2]);
  const Vec3 d = xp - (bary[0] * xa + bary[1] * xb + bary[2] * xc);
  if (region == 0) {
    const Vec3 n = (xb - xa).cross(xc - xa);
    const double len = n.norm();
    if (len < 1e-14) return false;
    u = (k.side / len) * n;
    C = u.dot(d) - k.thickness;
  } else {
    const double len = d.norm();
    if (len < 1e-12) return false;
    u = d / len;
    C = len - k.thickness;
  }
  return true;
}

inline bool contactState(const ContactConstraint& k, const double* x, double& C, Vec3& u,
                         double bary[3]) {
  return contactStateAt(CMap3(x + 3 * static_cast<long>(k.p)), k, x, C, u, bary);
}

// Contact of the midpoint m = (x_p + x_p2) / 2 of an edge with a triangle: C and its direction
// as for a vertex, grad_p C = grad_p2 C = u / 2, so the generalised inverse mass of the point
// is (w_p + w_p2) / 4 (the cords' points between vertices do the same).
template <bool kAcc>
void edgeContact(const ContactConstraint& k, double* x, const double* w, double& lambda,
                 double* acc) {
  const Vec3 mid = 0.5 * (at(x, k.p) + at(x, k.p2));
  double C, b[3];
  Vec3 u;
  if (!contactStateAt(mid, k, x, C, u, b)) return;
  if (C > 0.0 && lambda == 0.0) return;
  const double denom = 0.25 * (w[k.p] + w[k.p2]) + w[k.a] * b[0] * b[0] + w[k.b] * b[1] * b[1] +
                       w[k.c] * b[2] * b[2];
  if (denom == 0.0) return;
  const double total = std::max(lambda - C / denom, 0.0);
  const double dl = total - lambda;
  lambda = total;
  at(x, k.p) += (0.5 * w[k.p] * dl) * u;
  at(x, k.p2) += (0.5 * w[k.p2] * dl) * u;
  at(x, k.a) -= (w[k.a] * b[0] * dl) * u;
  at(x, k.b) -= (w[k.b] * b[1] * dl) * u;
  at(x, k.c) -= (w[k.c] * b[2] * dl) * u;
  if (kAcc) {
    accumulate(acc, k.p, 0.5 * u, total);
    accumulate(acc, k.p2, 0.5 * u, total);
    accumulate(acc, k.a, -b[0] * u, total);
    accumulate(acc, k.b, -b[1] * u, total);
    accumulate(acc, k.c, -b[2] * u, total);
  }
}

template <bool kAcc>
void contactSweep(const std::vector<ContactConstraint>& constraints, double* x, const double* w,
                  double* lambda, double* acc) {
  const int n = static_cast<int>(constraints.size());
  for (int c = 0; c < n; ++c) {
    const ContactConstraint& k = constraints[c];
    if (k.p2 >= 0) {
      edgeContact<kAcc>(k, x, w, lambda[c], acc);
      continue;
    }
    double C, b[3];
    Vec3 u;
    if (!contactState(k, x, C, u, b)) continue;
    if (C > 0.0 && lambda[c] == 0.0) continue;
    const double denom =
        w[k.p] + w[k.a] * b[0] * b[0] + w[k.b] * b[1] * b[1] + w[k.c] * b[2] * b[2];
    if (denom == 0.0) continue;
    double dl = -C / denom;
    // A contact only pushes: accumulated lambda stays >= 0.
    const double total = std::max(lambda[c] + dl, 0.0);
    dl = total - lambda[c];
    lambda[c] = total;
    at(x, k.p) += (w[k.p] * dl) * u;
    at(x, k.a) -= (w[k.a] * b[0] * dl) * u;
    at(x, k.b) -= (w[k.b] * b[1] * dl) * u;
    at(x, k.c) -= (w[k.c] * b[2] * dl) * u;
    if (kAcc) {
      accumulate(acc, k.p, u, total);
      accumulate(acc, k.a, -b[0] * u, total);
      accumulate(acc, k.b, -b[1] * u, total);
      accumulate(acc, k.c, -b[2] * u, total);
    }
  }
}

}  // namespace

void projectBending(const BendingConstraint* constraints, int count, double inv_dt2, double* x,
                    const double* w, double* lambda, double* acc) {
  if (acc)
    bendingSweep<true>(constraints, count, inv_dt2, x, w, lambda, acc);
  else
    bendingSweep<false>(constraints, count, inv_dt2, x, w, lambda, acc);
}

void projectAreas(const AreaConstraint* constraints, int count, double inv_dt2, double* x,
                  const double* w, double* lambda, double* acc) {
  if (acc)
    areaSweep<true>(constraints, count, inv_dt2, x, w, lambda, acc);
  else
    areaSweep<false>(constraints, count, inv_dt2, x, w, lambda, acc);
}

void projectCords(const std::vector<CordConstraint>& constraints, double inv_dt2,
                  const double* tips, double* x, const double* w, double* lambda, double* acc,
                  double max_pull) {
  if (acc)
    cordSweep<true>(constraints, inv_dt2, tips, x, w, lambda, acc, max_pull);
  else
    cordSweep<false>(constraints, inv_dt2, tips, x, w, lambda, acc, max_pull);
}

void projectAreaFloors(const AreaConstraint* constraints, int count, double* x, const double* w,
                       double* lambda, double* acc) {
  if (acc)
    areaFloorSweep<true>(constraints, count, x, w, lambda, acc);
  else
    areaFloorSweep<false>(constraints, count, x, w, lambda, acc);
}

void projectContacts(const std::vector<ContactConstraint>& constraints, double* x, const double* w,
                     double* lambda, double* acc) {
  if (acc)
    contactSweep<true>(constraints, x, w, lambda, acc);
  else
    contactSweep<false>(constraints, x, w, lambda, acc);
}

int closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                           const Eigen::Vector3d& b, const Eigen::Vector3d& c, double& ba,
                           double& bb, double& bc) {
  // Ericson 2005, "Real-Time Collision Detection", ClosestPtPointTriangle (Voronoi regions).
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    ba = 1.0, bb = 0.0, bc = 0.0;
    return 2;
  }
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {
    ba = 0.0, bb = 1.0, bc = 0.0;
    return 2;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    ba = 1.0 - v, bb = v, bc = 0.0;
    return 1;
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {
    ba = 0.0, bb = 0.0, bc = 1.0;
    return 2;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    ba = 1.0 - w, bb = 0.0, bc = w;
    return 1;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    ba = 0.0, bb = 1.0 - w, bc = w;
    return 1;
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  ba = 1.0 - v - w, bb = v, bc = w;
  return 0;
}

}  // namespace chordfit
