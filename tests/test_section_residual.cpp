// The fit's optional section residuals (inverse/forward_residual.h, --section-weight): one per
// tracing plane and leaflet after the tracing-point residuals, no loss, zero on the traced
// state, and the reported AvgD untouched.
#include <gtest/gtest.h>

#include "core/section_mismatch.h"
#include "inverse/fit_parameters.h"
#include "inverse/forward_residual.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

TEST(SectionResidual, AppendsOneResidualPerPlaneAndLeafletWithoutALoss) {
  const testing::TracedSeedClosure seed = testing::tracedSeedClosure("small-normal", 3);
  const ValveCase& traced = seed.traced;
  const Eigen::MatrixXd& open = traced.mesh.V;
  const inverse::FitParameterization parameters(
      traced, *traced.cords, inverse::ParameterMode::kScales, inverse::ParameterBounds{});
  const inverse::ResidualOptions points_only;
  inverse::ResidualOptions with_sections;
  with_sections.section_weight = 0.25;
  const inverse::ForwardResidual plain(traced, parameters, seed.settings, points_only);
  const inverse::ForwardResidual sections(traced, parameters, seed.settings, with_sections);

  ASSERT_EQ(plain.sectionCount(), 0);
  ASSERT_EQ(sections.pointCount(), plain.pointCount());
  ASSERT_EQ(sections.sectionCount(), 3 * 2) << "3 planes x 2 leaflets";
  ASSERT_EQ(sections.dataCount(), plain.dataCount() + 6);

  // The traced closed state: every section lies on its tracings, nothing strays.
  const Eigen::VectorXd on_traced = sections.dataResiduals(seed.closed_V);
  EXPECT_EQ(on_traced.tail(6).maxCoeff(), 0.0);
  EXPECT_EQ(on_traced.head(plain.pointCount()), plain.dataResiduals(seed.closed_V));

  // The open state strays far: r = sqrt(w E), and the cost adds 1/2 sum r^2 = w/2 sum E
  // (no Huber: E is already tolerant and capped, core/section_mismatch.h).
  const Eigen::VectorXd on_open = sections.dataResiduals(open);
  const Eigen::VectorXd E = SectionMismatch(traced).excess(open);
  ASSERT_GT(E.sum(), 0.0);
  for (int k = 0; k < 6; ++k)
    EXPECT_NEAR(on_open(plain.pointCount() + k), std::sqrt(0.25 * E(k)), 1e-12);
  const Eigen::VectorXd no_regularisation;
  EXPECT_NEAR(sections.cost(on_open, no_regularisation),
              plain.cost(plain.dataResiduals(open), no_regularisation) + 0.125 * E.sum(), 1e-9);
  EXPECT_EQ(sections.meanDeviation(open, on_open),
            plain.meanDeviation(open, plain.dataResiduals(open)))
      << "AvgD stays the tracing points' whole-mesh mean";
}

}  // namespace
}  // namespace chordfit
