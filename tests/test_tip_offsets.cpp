// The fit's judgement of PM tip offsets (tools/fit_report.h): an offset is determined by the
// tracings only beyond kTipOffsetDeterminedSds of its SD from 0, on either side; scales are never
// counted as tips, and without an uncertainty nothing is judged. The CLI tests see only fits
// whose offsets all stay within their SD (the quick-start case), so the "determined" branch is
// tested here.
#include <gtest/gtest.h>

#include "inverse/fit_cords.h"
#include "tools/fit_report.h"

namespace chordfit::cli {
namespace {

inverse::FitOutcome fitWithTips() {
  inverse::FitOutcome fit;
  fit.parameter_names = {"cord 0", "tip 0 x", "tip 0 y", "tip 0 z", "tip 1 x"};
  fit.parameter_is_scale = {true, false, false, false, false};
  fit.x = Eigen::VectorXd(5);
  fit.x << 1.2, 3.0, 0.5, -2.5, 2.0;
  fit.uncertainty.sd = Eigen::VectorXd::Constant(5, 1.0);
  fit.uncertainty.sd(0) = 0.01;  // a scale far beyond 2 SD from 0: still no tip
  fit.uncertainty.sensitivity = Eigen::VectorXd::Ones(5);
  fit.uncertainty.at_bound = std::vector<bool>(5, false);
  return fit;
}

TEST(TipOffsets, AreDeterminedOnlyBeyondTwoSdOfZeroOnEitherSide) {
  const inverse::FitOutcome fit = fitWithTips();
  ASSERT_TRUE(fit.uncertainty.ok());
  EXPECT_FALSE(tipOffsetDetermined(fit, 0)) << "a scale is not a tip offset";
  EXPECT_TRUE(tipOffsetDetermined(fit, 1)) << "3 SD";
  EXPECT_FALSE(tipOffsetDetermined(fit, 2)) << "0.5 SD";
  EXPECT_TRUE(tipOffsetDetermined(fit, 3)) << "-2.5 SD";
  EXPECT_FALSE(tipOffsetDetermined(fit, 4)) << "exactly 2 SD is within";
  const std::string line = tipOffsetsLine(fit);
  EXPECT_EQ(line.rfind("PM tips: 2 of 4 tip offsets determined (more than 2 SD from 0)", 0), 0u)
      << line;
}

// An offset held at its --tip-box bound is the bound's, not the tracings' (a probe's fit showed
// "tip anterolateral x | 8.000 | 2.061 (at bound) | yes").
TEST(TipOffsets, AtTheirBoundAreNotDetermined) {
  inverse::FitOutcome fit = fitWithTips();
  fit.uncertainty.at_bound[1] = true;
  EXPECT_FALSE(tipOffsetDetermined(fit, 1));
  EXPECT_TRUE(tipOffsetDetermined(fit, 3));
}

TEST(TipOffsets, AreNotJudgedWithoutAnUncertaintyOrWithoutTips) {
  inverse::FitOutcome fit = fitWithTips();
  fit.uncertainty.error = "too few residuals";
  EXPECT_FALSE(tipOffsetDetermined(fit, 1));
  EXPECT_EQ(tipOffsetsLine(fit), "");
  inverse::FitOutcome scales_only = fitWithTips();
  scales_only.parameter_is_scale.assign(5, true);
  EXPECT_EQ(tipOffsetsLine(scales_only), "");
}

}  // namespace
}  // namespace chordfit::cli
