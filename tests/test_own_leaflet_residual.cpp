// The fit's data residual measures each labelled tracing point to its own leaflet
// (inverse/forward_residual.h): never closer than the whole-mesh distance, strictly farther
// where the other leaflet passes nearer, and the reported AvgD stays the whole-mesh mean.
#include <gtest/gtest.h>

#include "core/metrics.h"
#include "inverse/fit_parameters.h"
#include "inverse/forward_residual.h"
#include "inverse/global_prefit.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

TEST(OwnLeafletResidual, IsTheOwnLeafletDistanceAndKeepsAvgDOnTheWholeMesh) {
  // The seed's closure, traced by a perfect reader: coapting leaflets, so points near the
  // coaptation line lie close to both leaflets.
  const testing::TracedSeedClosure seed = testing::tracedSeedClosure("small-normal", 6);
  const ValveCase& traced = seed.traced;
  const Eigen::MatrixXd& open = traced.mesh.V;
  const inverse::FitParameterization parameters(
      traced, *traced.cords, inverse::ParameterMode::kScales, inverse::ParameterBounds{});
  inverse::ResidualOptions own_options;
  inverse::ResidualOptions surface_options;
  surface_options.own_leaflet = false;
  const inverse::ForwardResidual own(traced, parameters, seed.settings, own_options);
  const inverse::ForwardResidual surface(traced, parameters, seed.settings, surface_options);

  // Open state against the closed tracings: far from both, the leaflets differ.
  const Eigen::VectorXd own_data = own.dataResiduals(open);
  const Eigen::VectorXd surface_data = surface.dataResiduals(open);
  ASSERT_EQ(own_data.size(), surface_data.size());
  int farther = 0;
  for (Eigen::Index i = 0; i < own_data.size(); ++i) {
    EXPECT_GE(own_data(i), surface_data(i) - 1e-12) << "point " << i;
    if (own_data(i) > surface_data(i) + 1e-6) ++farther;
  }
  EXPECT_GT(farther, 0) << "no point is nearer to the other leaflet in the open state";
  EXPECT_DOUBLE_EQ(own.meanDeviation(open, own_data), surface_data.mean());

  // The pre-fits' closures report the whole-mesh AvgD, as evaluate() does, not the mean of
  // their own-leaflet data (cords other than the traced ones, so the two differ).
  const CordSet shorter = inverse::scaleFreeCords(*traced.cords, 0.9);
  const inverse::ForwardEvaluation prefit_closure = inverse::closeForData(traced, shorter, own);
  ASSERT_TRUE(prefit_closure.ok()) << prefit_closure.error;
  EXPECT_DOUBLE_EQ(prefit_closure.mean_deviation_mm,
                   own.surfaceDistances(prefit_closure.closed_V).mean());
  EXPECT_GT(prefit_closure.data.mean(), prefit_closure.mean_deviation_mm);

  // On the traced closed state every point lies on its own leaflet's surface.
  const Eigen::VectorXd on_surface = own.dataResiduals(seed.closed_V);
  EXPECT_LT(on_surface.maxCoeff(), 1e-9);
}

}  // namespace
}  // namespace chordfit
