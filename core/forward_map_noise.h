// Smoothness of a sampled 1-D map q(s) on a uniform grid: how far the samples scatter about
// a local quadratic (the map's "noise"), against how much q changes over a given step
// (the "signal" a finite-difference Jacobian would see). The inverse problem needs
// noise << signal at the chosen finite-difference step.
#pragma once

#include <vector>

namespace chordfit {

struct MapNoise {
  double rms = 0.0;    // RMS of (sample - local quadratic fit), over interior samples
  double max = 0.0;    // largest |sample - local quadratic fit|
  double slope = 0.0;  // dq/ds at the grid's centre, from a quadratic fit of all samples
};

// s, q  same size, s uniform and increasing; half_window >= 2 points each side.
// Each interior sample i is compared with the least-squares quadratic through samples
// i - half_window .. i + half_window excluding i itself (leave-one-out, so the fit cannot
// absorb the sample's own noise). A window wider than the samples leaves no interior sample:
// rms and max 0.
MapNoise mapNoise(const std::vector<double>& s, const std::vector<double>& q, int half_window);

// The s where the sampled map turns: its lowest or highest sample, at least max(2, n/10)
// samples from either end and rising above both ends by more than 10 * `noise` (so a noisy
// flat map has none); NaN when there is none. Near it the change over a step is small by
// nature, and a slope taken there says nothing about the noise.
double turningScale(const std::vector<double>& s, const std::vector<double>& q, double noise);

}  // namespace chordfit
