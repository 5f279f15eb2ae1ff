#include "core/graph_distance.h"

#include <functional>
#include <limits>
#include <queue>
#include <utility>

namespace chordfit {

Eigen::VectorXd edgeGraphDistance(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                  const std::vector<int>& sources) {
  const Eigen::Index n = V.rows();
  std::vector<std::vector<int>> neighbours(n);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      neighbours[F(f, k)].push_back(F(f, (k + 1) % 3));
      neighbours[F(f, (k + 1) % 3)].push_back(F(f, k));
    }
  }
  Eigen::VectorXd distance = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::infinity());
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for (int s : sources) {
    distance(s) = 0.0;
    queue.push({0.0, s});
  }
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > distance(v)) continue;
    for (int w : neighbours[v]) {
      const double candidate = d + (V.row(v) - V.row(w)).norm();
      if (candidate < distance(w)) {
        distance(w) = candidate;
        queue.push({candidate, w});
      }
    }
  }
  return distance;
}

}  // namespace chordfit
