// Cord spans in a closed state (core/cord_insertion.h closedSpans): taut cords end at their rest
// length, slack ones short of it, in agreement with the simulator's cord forces, with the
// insertions at their points and spread over the insertion patch.
#include <gtest/gtest.h>

#include "core/closure_model.h"
#include "core/cord_insertion.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

TEST(ClosedSpans, TautCordsEndAtTheirRestLengthAndSlackOnesShortOfIt) {
  const testing::BundledCase bundled = testing::bundledCase("small-normal");
  const CordSet& cords = *bundled.valve_case.cords;
  for (double radius : {0.0, 2.0}) {
    SimulationSettings settings = bundled.settings;
    settings.cord_insertion_radius_mm = radius;
    const SimulationResult closed = simulateClosure(bundled.valve_case, cords, settings);
    ASSERT_TRUE(closed.ok()) << closed.error;
    const Eigen::VectorXd spans =
        closedSpans(cords, cordInsertions(bundled.valve_case.mesh, cords, radius), closed.V);
    ASSERT_EQ(spans.size(), static_cast<Eigen::Index>(cords.cords.size()));
    int taut = 0, slack = 0;
    for (std::size_t c = 0; c < cords.cords.size(); ++c) {
      const double rest = cords.cords[c].rest_length;
      const double span = spans(static_cast<Eigen::Index>(c));
      if (closed.cord_force(static_cast<Eigen::Index>(c)) > 0.0) {
        ++taut;
        EXPECT_NEAR(span, rest, kSlackMarginMm) << "taut cord " << c << ", radius " << radius;
      } else {
        ++slack;
        EXPECT_LT(span, rest - kSlackMarginMm) << "slack cord " << c << ", radius " << radius;
      }
    }
    EXPECT_GT(taut, 0);
    EXPECT_GT(slack, 0);
  }
}

}  // namespace
}  // namespace chordfit
