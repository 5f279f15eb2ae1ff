// The fit's parameter uncertainty (inverse/fit_uncertainty.h) against hand-computed linear
// least-squares answers.
#include <cmath>

#include <gtest/gtest.h>

#include "inverse/fit_uncertainty.h"

namespace chordfit::inverse {
namespace {

constexpr double kTight = 1e-12;

const Eigen::VectorXd kNoBoundLower = Eigen::VectorXd::Constant(2, -10.0);
const Eigen::VectorXd kNoBoundUpper = Eigen::VectorXd::Constant(2, 10.0);

TEST(FitUncertainty, IsTheScaledInverseNormalMatrixOfALinearFit) {
  // Four residuals, one parameter seen by all with slope 1: sigma^2 = sum r^2 / (4 - 1),
  // C = sigma^2 / 4.
  Eigen::MatrixXd J = Eigen::MatrixXd::Ones(4, 1);
  Eigen::VectorXd r(4);
  r << 0.1, -0.1, 0.2, -0.2;
  const FitUncertainty u =
      fitUncertainty(J, r, {4}, 1.0, Eigen::MatrixXd(), Eigen::VectorXd::Zero(1),
                     Eigen::VectorXd::Constant(1, -1.0), Eigen::VectorXd::Constant(1, 1.0));
  ASSERT_TRUE(u.ok()) << u.error;
  const double sigma2 = (0.01 + 0.01 + 0.04 + 0.04) / 3.0;
  EXPECT_NEAR(u.sigma_mm, std::sqrt(sigma2), kTight);
  EXPECT_NEAR(u.sd(0), std::sqrt(sigma2 / 4.0), kTight);
  EXPECT_NEAR(u.sensitivity(0), 2.0, kTight);
  EXPECT_FALSE(u.at_bound[0]);
}

TEST(FitUncertainty, AnUnseenParameterKeepsThePriorsSpreadAndABoundIsFlagged) {
  // Parameter 0 moves every residual, parameter 1 none: only the prior (0.5 per unit, as the
  // fit's seed term) holds it, C_11 = sigma^2 / 0.25.
  Eigen::MatrixXd J(3, 2);
  J << 1, 0, 2, 0, 1, 0;
  Eigen::VectorXd r(3);
  r << 0.3, -0.3, 0.0;
  Eigen::MatrixXd A = 0.5 * Eigen::MatrixXd::Identity(2, 2);
  Eigen::VectorXd x(2);
  x << 10.0, 0.0;  // parameter 0 at its upper bound
  const FitUncertainty u = fitUncertainty(J, r, {3}, 1.0, A, x, kNoBoundLower, kNoBoundUpper);
  ASSERT_TRUE(u.ok()) << u.error;
  const double sigma2 = 0.18 / 1.0;
  EXPECT_NEAR(u.sd(1), std::sqrt(sigma2 / 0.25), kTight);
  EXPECT_NEAR(u.sd(0), std::sqrt(sigma2 / (6.0 + 0.25)), kTight);
  EXPECT_EQ(u.sensitivity(1), 0.0);
  EXPECT_TRUE(u.at_bound[0]);
  EXPECT_FALSE(u.at_bound[1]);
  // Without the prior the unseen parameter makes the normal matrix singular.
  EXPECT_FALSE(
      fitUncertainty(J, r, {3}, 1.0, Eigen::MatrixXd(), x, kNoBoundLower, kNoBoundUpper).ok());
}

TEST(FitUncertainty, HuberWeightsTracingPointsBeyondDeltaButNotTheSectionResiduals) {
  // Residual 0 (a tracing point, 3 mm > delta = 1) counts with weight 1/3: w r^2 = 3 and its
  // Jacobian row scaled by sqrt(1/3). Residual 2 (a section residual) counts in full.
  Eigen::MatrixXd J(3, 1);
  J << 1, 1, 1;
  Eigen::VectorXd r(3);
  r << 3.0, 0.5, 2.0;
  const FitUncertainty u =
      fitUncertainty(J, r, {2}, 1.0, Eigen::MatrixXd(), Eigen::VectorXd::Zero(1),
                     Eigen::VectorXd::Constant(1, -1.0), Eigen::VectorXd::Constant(1, 1.0));
  ASSERT_TRUE(u.ok()) << u.error;
  const double sigma2 = (3.0 + 0.25 + 4.0) / 2.0;
  EXPECT_NEAR(u.sigma_mm, std::sqrt(sigma2), kTight);
  EXPECT_NEAR(u.sd(0), std::sqrt(sigma2 / (1.0 / 3.0 + 1.0 + 1.0)), kTight);
}

TEST(FitUncertainty, CorrelatedResidualsAlongATracingInflateTheVarianceByTheirCorrelationTime) {
  // Residual deviations 1, 1, -1, -1, ... along one polyline: rho_1 = 1/7 (sum of 7 lag-1
  // products = 1, variance 1), rho_2 = -1 stops the sum, so tau = 1 + 2/7. The same residuals
  // as eight one-point polylines have no pairs: tau = 1.
  Eigen::VectorXd r(8);
  r << 1, 1, -1, -1, 1, 1, -1, -1;
  const Eigen::MatrixXd J = Eigen::MatrixXd::Ones(8, 1);
  const Eigen::VectorXd x = Eigen::VectorXd::Zero(1), lo = Eigen::VectorXd::Constant(1, -1.0),
                        hi = Eigen::VectorXd::Constant(1, 1.0);
  const FitUncertainty along = fitUncertainty(J, r, {8}, 10.0, Eigen::MatrixXd(), x, lo, hi);
  const FitUncertainty apart =
      fitUncertainty(J, r, {1, 1, 1, 1, 1, 1, 1, 1}, 10.0, Eigen::MatrixXd(), x, lo, hi);
  ASSERT_TRUE(along.ok() && apart.ok());
  EXPECT_NEAR(along.correlation_time, 9.0 / 7.0, kTight);
  EXPECT_EQ(apart.correlation_time, 1.0);
  EXPECT_NEAR(along.sd(0), apart.sd(0) * std::sqrt(9.0 / 7.0), kTight);
}

TEST(FitUncertainty, RefusesTooFewResidualsAndInconsistentSizes) {
  const Eigen::MatrixXd J = Eigen::MatrixXd::Ones(2, 2);
  EXPECT_FALSE(fitUncertainty(J, Eigen::VectorXd::Zero(2), {2}, 1.0, Eigen::MatrixXd(),
                              Eigen::VectorXd::Zero(2), kNoBoundLower, kNoBoundUpper)
                   .ok());
  EXPECT_FALSE(fitUncertainty(Eigen::MatrixXd::Ones(3, 2), Eigen::VectorXd::Zero(2), {2}, 1.0,
                              Eigen::MatrixXd(), Eigen::VectorXd::Zero(2), kNoBoundLower,
                              kNoBoundUpper)
                   .ok());
}

}  // namespace
}  // namespace chordfit::inverse
