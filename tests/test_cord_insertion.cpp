// The cord insertion patch (core/cord_insertion.h): a cord's tension spread over the rest
// surface with a bump of fixed physical radius, the same load on every mesh.
#include <cmath>
#include <numeric>

#include <gtest/gtest.h>

#include "core/cord_insertion.h"
#include "tests/test_sheets.h"

namespace chordfit {
namespace {

constexpr double kDisc = 10.0;   // mm, disc radius
constexpr double kRadius = 2.0;  // mm, patch radius
constexpr double kMoment = 1.0;  // mm^2: E|y - p0|^2 of the bump (1 - d^2/r^2)^2 is r^2 / 4

struct Disc {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
};

Disc disc(int rings) {
  Disc d;
  Eigen::VectorXi boundary;
  testing::makeDisc(kDisc, rings, d.V, d.F, boundary);
  return d;
}

double secondMoment(const Disc& d, const CordInsertionWeights& w, const Eigen::Vector3d& p0) {
  double moment = 0.0;
  for (std::size_t m = 0; m < w.vertices.size(); ++m)
    moment += w.weights[m] * (d.V.row(w.vertices[m]).transpose() - p0).squaredNorm();
  return moment;
}

TEST(CordInsertion, RadiusZeroIsThePointItself) {
  const Disc d = disc(5);
  const CordInsertionWeights w = cordInsertionWeights(d.V, d.F, {3, 0, 1}, {0.5, 0.5, 0.0}, 0.0);
  EXPECT_EQ(w.vertices, (std::vector<int>{3, 0, 1}));  // as given: the simulator's sum order
  EXPECT_EQ(w.weights, (std::vector<double>{0.5, 0.5, 0.0}));
}

TEST(CordInsertion, SpreadsTheSameLoadOverEveryMesh) {
  // The centre of the disc at 1.0, 0.5 and 0.25 mm edges: weights positive and summing to 1,
  // within the radius (plus one edge, the hat functions' reach), centred on the insertion
  // (hat functions reproduce linear functions, and the bump is symmetric), and spread as the
  // bump is, r^2 / 4, up to the O(h^2) of the lumping.
  for (int rings : {10, 20, 40}) {
    const Disc d = disc(rings);
    const double edge = kDisc / rings;
    const CordInsertionWeights w = cordInsertionWeights(d.V, d.F, {0}, {1.0}, kRadius);
    EXPECT_NEAR(std::accumulate(w.weights.begin(), w.weights.end(), 0.0), 1.0, 1e-12);
    for (std::size_t m = 0; m < w.vertices.size(); ++m) {
      EXPECT_GT(w.weights[m], 0.0);
      EXPECT_LT(d.V.row(w.vertices[m]).norm(), kRadius + edge + 1e-9);
    }
    EXPECT_LT(insertionPosition(w, d.V).norm(), 1e-3) << rings << " rings";
    EXPECT_NEAR(secondMoment(d, w, Eigen::Vector3d::Zero()), kMoment, 0.5 * edge * edge)
        << rings << " rings";
  }
}

TEST(CordInsertion, OffCentreInsertionBetweenVerticesIsCentredOnItsPoint) {
  const Disc d = disc(20);
  // A point of the triangle (0, 1, 2) near the centre.
  const std::vector<int> vertices{d.F(0, 0), d.F(0, 1), d.F(0, 2)};
  const std::vector<double> weights{0.2, 0.5, 0.3};
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  for (int m = 0; m < 3; ++m) p0 += weights[m] * d.V.row(vertices[m]).transpose();
  const CordInsertionWeights w = cordInsertionWeights(d.V, d.F, vertices, weights, kRadius);
  EXPECT_LT((insertionPosition(w, d.V) - p0).norm(), 1e-3);
  EXPECT_GT(w.vertices.size(), 20u);
}

TEST(CordInsertion, ATinyRadiusOnACoarseMeshIsThePointsBarycentricWeights) {
  const Disc d = disc(4);  // 2.5 mm edges
  const std::vector<int> vertices{d.F(5, 0), d.F(5, 1), d.F(5, 2)};
  const std::vector<double> weights{0.6, 0.3, 0.1};
  const CordInsertionWeights w = cordInsertionWeights(d.V, d.F, vertices, weights, 0.05);
  ASSERT_EQ(w.vertices.size(), 3u);
  for (int m = 0; m < 3; ++m) {
    const auto at = std::find(w.vertices.begin(), w.vertices.end(), vertices[m]);
    ASSERT_NE(at, w.vertices.end());
    EXPECT_NEAR(w.weights[at - w.vertices.begin()], weights[m], 0.02);
  }
}

}  // namespace
}  // namespace chordfit
