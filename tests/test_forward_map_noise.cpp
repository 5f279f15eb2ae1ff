#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "core/forward_map_noise.h"

namespace chordfit {
namespace {

TEST(MapNoise, IsZeroForAQuadraticAndRecoversItsSlope) {
  std::vector<double> s, q;
  for (int i = 0; i <= 100; ++i) {
    s.push_back(0.95 + 0.001 * i);
    q.push_back(3.0 - 2.0 * (s.back() - 1.0) + 40.0 * std::pow(s.back() - 1.0, 2));
  }
  const MapNoise noise = mapNoise(s, q, 5);
  EXPECT_LT(noise.rms, 1e-12);
  EXPECT_NEAR(noise.slope, -2.0, 1e-9);
}

TEST(MapNoise, MeasuresAlternatingNoiseOnASmoothMap) {
  std::vector<double> s, q;
  const double amplitude = 1e-3;
  for (int i = 0; i <= 100; ++i) {
    s.push_back(0.95 + 0.001 * i);
    q.push_back(std::sin(s.back()) + (i % 2 ? amplitude : -amplitude));
  }
  const MapNoise noise = mapNoise(s, q, 5);
  // Leave-one-out: the quadratic through the 10 neighbours (5 of each sign) predicts the left-out
  // sample's noise as -(7/85) of its amplitude, so every residual is 92/85 = 1.0824 of it (the
  // smooth curve's part is ~3e-9 of the amplitude). A fit that kept the sample itself would
  // absorb part of its noise: 0.8578 of the amplitude. Computed independently (a quadratic
  // least-squares fit per window, in Python) for this signal.
  EXPECT_NEAR(noise.rms, 92.0 / 85.0 * amplitude, 0.01 * amplitude);
  EXPECT_NEAR(noise.max, 92.0 / 85.0 * amplitude, 0.01 * amplitude);
  EXPECT_NEAR(noise.slope, std::cos(1.0), 1e-3);
}

// sweep-cord --window 1073741824 used to crash here: i + half_window overflowed int and the
// loop read far outside the samples.
TEST(MapNoise, AWindowWiderThanTheSamplesLeavesNoInteriorSampleInsteadOfOverflowing) {
  std::vector<double> s, q;
  for (int i = 0; i <= 10; ++i) {
    s.push_back(0.99 + 0.002 * i);
    q.push_back(2.0 * s.back());
  }
  for (const int window : {11, 1073741824, std::numeric_limits<int>::max()}) {
    const MapNoise noise = mapNoise(s, q, window);
    EXPECT_EQ(noise.rms, 0.0) << window;
    EXPECT_EQ(noise.max, 0.0) << window;
    EXPECT_NEAR(noise.slope, 2.0, 1e-9) << window;
  }
}

// A map with its minimum inside the range turns there; a monotonic one and a flat noisy one
// do not (sweep-cord's verdict names the turning point instead of calling the map noisy).
TEST(TurningScale, FindsAnInteriorMinimumAndNothingOnAMonotonicOrFlatMap) {
  std::vector<double> s, bowl, line, flat;
  for (int i = 0; i <= 40; ++i) {
    s.push_back(0.9 + 0.005 * i);
    bowl.push_back((s.back() - 0.97) * (s.back() - 0.97));
    line.push_back(2.0 * s.back());
    flat.push_back(i % 2 == 0 ? 1e-4 : -1e-4);
  }
  EXPECT_NEAR(turningScale(s, bowl, 1e-6), 0.97, 1e-9);
  EXPECT_TRUE(std::isnan(turningScale(s, line, 1e-6)));
  EXPECT_TRUE(std::isnan(turningScale(s, flat, 1e-4))) << "noise, not a turn";
  EXPECT_TRUE(std::isnan(turningScale(s, bowl, 1.0))) << "within ten times the noise";
}

}  // namespace
}  // namespace chordfit
