// The contact detector (core/contact.h) against an exhaustive search: its Verlet list and the
// per-step displacement bound may only save work, never change the constraints.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/contact.h"
#include "core/xpbd_constraints.h"

namespace chordfit {
namespace {

using Vec3 = Eigen::Vector3d;

// Two parallel square sheets of n x n vertices, `spacing` apart in-plane, `gap` apart in z.
void makeTwoSheets(int n, double spacing, double gap, Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  const int per_sheet = n * n;
  V.resize(2 * per_sheet, 3);
  F.resize(2 * 2 * (n - 1) * (n - 1), 3);
  int f = 0;
  for (int s = 0; s < 2; ++s) {
    const int base = s * per_sheet;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) V.row(base + i * n + j) << i * spacing, j * spacing, s * gap;
    for (int i = 0; i + 1 < n; ++i)
      for (int j = 0; j + 1 < n; ++j) {
        const int v00 = base + i * n + j, v10 = v00 + n, v01 = v00 + 1, v11 = v10 + 1;
        F.row(f++) << v00, v10, v11;
        F.row(f++) << v00, v11, v01;
      }
  }
}

// Every (triangle, vertex) pair within thickness + margin at x_pred that the detector's
// rules admit (contact.h), in its order (triangle, then vertex); the side rule is the
// detector's own (contactConstraint), the pair selection is what is checked.
std::vector<ContactConstraint> exhaustiveContacts(const Eigen::MatrixXd& V_rest,
                                                  const Eigen::MatrixXi& F,
                                                  const ContactOptions& options,
                                                  const std::vector<double>& x_start,
                                                  const std::vector<double>& x_pred,
                                                  const std::vector<double>& w) {
  const auto at = [](const std::vector<double>& x, int i) {
    return Vec3(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
  };
  const double reach = options.thickness_mm + options.margin_mm;
  std::vector<ContactConstraint> out;
  for (int f = 0; f < F.rows(); ++f) {
    const int ia = F(f, 0), ib = F(f, 1), ic = F(f, 2);
    for (int p = 0; p < V_rest.rows(); ++p) {
      if (p == ia || p == ib || p == ic) continue;
      if (w[p] == 0.0 && w[ia] == 0.0 && w[ib] == 0.0 && w[ic] == 0.0) continue;
      bool excluded = false;
      for (int v : {ia, ib, ic})
        excluded = excluded || (V_rest.row(v) - V_rest.row(p)).norm() < options.exclusion_radius_mm;
      if (excluded) continue;
      const Vec3 xp = at(x_pred, p), a = at(x_pred, ia), b = at(x_pred, ib), c = at(x_pred, ic);
      double ba, bb, bc;
      closestPointOnTriangle(xp, a, b, c, ba, bb, bc);
      if ((xp - (ba * a + bb * b + bc * c)).squaredNorm() >= reach * reach) continue;
      out.push_back(
          contactConstraint(p, ia, ib, ic, x_start.data(), x_pred.data(), options.thickness_mm));
    }
  }
  return out;
}

TEST(ContactDetector, MatchesExhaustiveSearchOverARandomWalk) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  makeTwoSheets(9, 0.8, 1.2, V, F);
  ContactOptions options;
  options.thickness_mm = 1.0;
  options.margin_mm = 0.25;
  options.skin_mm = 1.0;
  options.exclusion_radius_mm = 2.5;
  ContactDetector detector(V, F, options);

  std::vector<double> w(V.rows(), 1.0);
  for (int i = 0; i < 9; ++i) w[i] = 0.0;  // one fixed edge, as the annulus ring
  std::vector<double> x_start(3 * V.rows());
  for (int i = 0; i < V.rows(); ++i)
    for (int d = 0; d < 3; ++d) x_start[3 * i + d] = V(i, d);

  // Mostly small steps (the list is reused and the displacement bound skips pairs) with an
  // occasional large one (the list is rebuilt); the sheets drift together and apart.
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<ContactConstraint> found;
  int steps = 0, total_contacts = 0;
  for (int step = 0; step < 120; ++step, ++steps) {
    const double amplitude = step % 25 == 24 ? 0.4 : 0.03;
    const double drift = 0.01 * std::sin(0.1 * step);
    std::vector<double> x_pred = x_start;
    for (int i = 0; i < V.rows(); ++i) {
      if (w[i] == 0.0) continue;
      for (int d = 0; d < 3; ++d) x_pred[3 * i + d] += amplitude * unit(random);
      x_pred[3 * i + 2] += i >= 81 ? -drift : drift;
    }
    detector.detect(x_start.data(), x_pred.data(), w.data(), found);
    const std::vector<ContactConstraint> expected =
        exhaustiveContacts(V, F, options, x_start, x_pred, w);
    ASSERT_EQ(found.size(), expected.size()) << "step " << step;
    for (size_t k = 0; k < found.size(); ++k) {
      EXPECT_EQ(found[k].p, expected[k].p) << "step " << step << " pair " << k;
      EXPECT_EQ(found[k].a, expected[k].a);
      EXPECT_EQ(found[k].b, expected[k].b);
      EXPECT_EQ(found[k].c, expected[k].c);
      EXPECT_EQ(found[k].side, expected[k].side);
    }
    total_contacts += static_cast<int>(found.size());
    x_start = x_pred;
  }
  // The walk exercised both paths: contacts were found, and the list was reused.
  EXPECT_GT(total_contacts, 100);
  EXPECT_GT(detector.rebuilds(), 1);
  EXPECT_LT(detector.rebuilds(), steps / 2);
}

}  // namespace
}  // namespace chordfit
