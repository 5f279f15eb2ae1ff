// Shortest-path distances along mesh edges (Dijkstra on the edge graph, edge weight =
// Euclidean edge length). An upper bound of the geodesic distance, close to it on a
// well-shaped mesh; enough to tell "how far from the free edge" a vertex sits.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace chordfit {

// V #V by 3, F #F by 3, sources: vertex indices at distance 0.
// Returns #V distances (infinity for vertices not connected to any source).
Eigen::VectorXd edgeGraphDistance(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                  const std::vector<int>& sources);

}  // namespace chordfit
