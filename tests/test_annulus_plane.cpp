#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "core/annulus_plane.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

constexpr double kTolerance = 1e-9;

TEST(FitPlane, RecoversATiltedSaddlesPlane) {
  // Saddle z = 3 cos(2 phi) on an ellipse: symmetric, so its least-squares plane is z = 0.
  const int n = 72;
  Eigen::MatrixXd P(n, 3);
  for (int i = 0; i < n; ++i) {
    const double phi = 2.0 * M_PI * i / n;
    P.row(i) << 14.0 * std::cos(phi), 17.5 * std::sin(phi), 3.0 * std::cos(2.0 * phi);
  }
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 0.5).normalized())).toRotationMatrix();
  const Eigen::Vector3d shift(5.0, -3.0, 12.0);
  const Eigen::MatrixXd Q = (P * R.transpose()).rowwise() + shift.transpose();
  const Plane plane = fitPlane(Q);
  EXPECT_NEAR(std::abs(plane.normal.dot(R * Eigen::Vector3d::UnitZ())), 1.0, kTolerance);
  EXPECT_NEAR((plane.centre - shift).norm(), 0.0, kTolerance);
}

TEST(OpenAnnulusFrame, PointsTheNormalAwayFromTheHangingLeaflets) {
  ValveCase c = testing::tinyConeCase();
  AnnulusFrame frame = openAnnulusFrame(c.mesh);
  EXPECT_NEAR(frame.plane.normal.z(), 1.0, kTolerance);
  EXPECT_NEAR(frame.a.x(), 1.0, kTolerance);  // anterior columns are at +x
  EXPECT_NEAR(frame.l.y(), 1.0, kTolerance);
  // Flip the cone upside down: the normal follows the leaflets.
  c.mesh.V.col(2) *= -1.0;
  frame = openAnnulusFrame(c.mesh);
  EXPECT_NEAR(frame.plane.normal.z(), -1.0, kTolerance);
}

TEST(AnnulusFrameFromRing, KeepsTheReferenceOrientation) {
  const ValveCase c = testing::tinyConeCase();
  const AnnulusFrame open = openAnnulusFrame(c.mesh);
  Eigen::MatrixXd closed = c.annulus_closed * 0.9;
  closed.col(2).array() += 2.0;
  const AnnulusFrame frame = annulusFrameFromRing(closed, c.mesh, open);
  EXPECT_NEAR(frame.plane.normal.z(), 1.0, kTolerance);
  EXPECT_NEAR(frame.plane.centre.z(), 2.0, kTolerance);
}

}  // namespace
}  // namespace chordfit
