#include "core/forward_map_noise.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace chordfit {

namespace {

// Least-squares quadratic through (s_k - s0, q_k) for k in `indices`; returns coefficients
// (c0, c1, c2) of c0 + c1 t + c2 t^2 with t = s - s0.
Eigen::Vector3d quadraticFit(const std::vector<double>& s, const std::vector<double>& q,
                             const std::vector<int>& indices, double s0) {
  Eigen::MatrixXd A(indices.size(), 3);
  Eigen::VectorXd b(indices.size());
  for (std::size_t r = 0; r < indices.size(); ++r) {
    const double t = s[indices[r]] - s0;
    A.row(r) << 1.0, t, t * t;
    b(r) = q[indices[r]];
  }
  return A.colPivHouseholderQr().solve(b);
}

}  // namespace

MapNoise mapNoise(const std::vector<double>& s, const std::vector<double>& q, int half_window) {
  MapNoise noise;
  const int n = static_cast<int>(std::min(s.size(), q.size()));
  if (n < 3) return noise;
  half_window = std::max(2, half_window);
  double sum_squares = 0.0;
  int count = 0;
  // i < n - half_window, not i + half_window < n: a huge window must leave no interior
  // sample, not overflow into a negative bound and index far outside the samples.
  for (int i = half_window; i < n - half_window; ++i) {
    std::vector<int> neighbours;
    for (int k = i - half_window; k <= i + half_window; ++k) {
      if (k != i) neighbours.push_back(k);
    }
    const double residual = q[i] - quadraticFit(s, q, neighbours, s[i])(0);
    sum_squares += residual * residual;
    noise.max = std::max(noise.max, std::abs(residual));
    ++count;
  }
  noise.rms = count > 0 ? std::sqrt(sum_squares / count) : 0.0;
  std::vector<int> all(n);
  for (int k = 0; k < n; ++k) all[k] = k;
  noise.slope = quadraticFit(s, q, all, s[n / 2])(1);
  return noise;
}

double turningScale(const std::vector<double>& s, const std::vector<double>& q, double noise) {
  const std::size_t n = q.size(), margin = std::max<std::size_t>(2, n / 10);
  if (n < 2 * margin + 1) return NAN;
  const auto [lo, hi] = std::minmax_element(q.begin(), q.end());
  for (auto it : {lo, hi}) {
    const std::size_t i = static_cast<std::size_t>(it - q.begin());
    const double rise = std::min(std::abs(q.front() - *it), std::abs(q.back() - *it));
    if (i >= margin && i + margin < n && rise > 10.0 * noise) return s[i];
  }
  return NAN;
}

}  // namespace chordfit
