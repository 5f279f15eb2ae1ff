#include "core/mesh_topology.h"

#include <algorithm>
#include <array>
#include <queue>

namespace chordfit {
namespace {

// One face corner seen from the edge opposite it: (a, b) = sorted edge, f = face, c = corner.
struct EdgeRecord {
  int a, b, f, c;
  bool operator<(const EdgeRecord& o) const {
    if (a != o.a) return a < o.a;
    if (b != o.b) return b < o.b;
    return f < o.f;
  }
};

// All 3 #F edge records sorted by (edge, face): the records of one edge are contiguous.
std::vector<EdgeRecord> sortedEdgeRecords(const Eigen::MatrixXi& F) {
  std::vector<EdgeRecord> records;
  records.reserve(static_cast<size_t>(F.rows()) * 3);
  for (int f = 0; f < F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int u = F(f, (c + 1) % 3), v = F(f, (c + 2) % 3);
      records.push_back({std::min(u, v), std::max(u, v), f, c});
    }
  }
  std::sort(records.begin(), records.end());
  return records;
}

}  // namespace

Eigen::MatrixXi uniqueEdges(const Eigen::MatrixXi& F) {
  Eigen::MatrixXi E, EF, EI;
  edgeFlaps(F, E, EF, EI);
  return E;
}

void edgeFlaps(const Eigen::MatrixXi& F, Eigen::MatrixXi& E, Eigen::MatrixXi& EF,
               Eigen::MatrixXi& EI) {
  const std::vector<EdgeRecord> records = sortedEdgeRecords(F);
  std::vector<std::array<int, 6>> rows;  // a, b, f0, c0, f1, c1
  rows.reserve(records.size() / 2 + 1);
  for (size_t r = 0; r < records.size();) {
    size_t s = r + 1;
    while (s < records.size() && records[s].a == records[r].a && records[s].b == records[r].b) ++s;
    std::array<int, 6> row{records[r].a, records[r].b, records[r].f, records[r].c, -1, -1};
    if (s - r >= 2) {
      row[4] = records[r + 1].f;
      row[5] = records[r + 1].c;
    }
    rows.push_back(row);
    r = s;
  }
  const int n = static_cast<int>(rows.size());
  E.resize(n, 2);
  EF.resize(n, 2);
  EI.resize(n, 2);
  for (int e = 0; e < n; ++e) {
    E(e, 0) = rows[e][0];
    E(e, 1) = rows[e][1];
    EF(e, 0) = rows[e][2];
    EI(e, 0) = rows[e][3];
    EF(e, 1) = rows[e][4];
    EI(e, 1) = rows[e][5];
  }
}

int nonManifoldEdgeCount(const Eigen::MatrixXi& F) {
  const std::vector<EdgeRecord> records = sortedEdgeRecords(F);
  int count = 0;
  for (size_t r = 0; r < records.size();) {
    size_t s = r + 1;
    while (s < records.size() && records[s].a == records[r].a && records[s].b == records[r].b) ++s;
    if (s - r > 2) ++count;
    r = s;
  }
  return count;
}

Eigen::MatrixXi bendingQuads(const Eigen::MatrixXi& F) {
  Eigen::MatrixXi E, EF, EI;
  edgeFlaps(F, E, EF, EI);
  std::vector<std::array<int, 4>> quads;
  for (int e = 0; e < E.rows(); ++e) {
    if (EF(e, 1) < 0) continue;
    const int f0 = EF(e, 0), c0 = EI(e, 0);
    // In face f0 the edge runs corner c0+1 -> c0+2 in winding order.
    const int i = F(f0, (c0 + 1) % 3), j = F(f0, (c0 + 2) % 3), k = F(f0, c0);
    const int l = F(EF(e, 1), EI(e, 1));
    quads.push_back({i, j, k, l});
  }
  Eigen::MatrixXi Q(static_cast<int>(quads.size()), 4);
  for (int b = 0; b < Q.rows(); ++b)
    for (int c = 0; c < 4; ++c) Q(b, c) = quads[b][c];
  return Q;
}

std::vector<std::vector<int>> boundaryLoops(const Eigen::MatrixXi& F) {
  Eigen::MatrixXi E, EF, EI;
  edgeFlaps(F, E, EF, EI);
  // Boundary edges, with their direction in the winding of their single face.
  std::vector<std::array<int, 2>> directed;
  for (int e = 0; e < E.rows(); ++e) {
    if (EF(e, 1) >= 0) continue;
    const int f = EF(e, 0), c = EI(e, 0);
    directed.push_back({F(f, (c + 1) % 3), F(f, (c + 2) % 3)});
  }
  if (directed.empty()) return {};
  int max_vertex = 0;
  for (const auto& d : directed) max_vertex = std::max({max_vertex, d[0], d[1]});
  // Incident boundary edges per vertex, as (edge id) lists in increasing edge order.
  std::vector<std::vector<int>> incident(max_vertex + 1);
  for (int b = 0; b < static_cast<int>(directed.size()); ++b) {
    incident[directed[b][0]].push_back(b);
    incident[directed[b][1]].push_back(b);
  }
  std::vector<char> used(directed.size(), 0);
  std::vector<std::vector<int>> loops;
  for (int start = 0; start <= max_vertex; ++start) {
    while (true) {
      // First unused boundary edge at `start`, preferring one leaving in winding order.
      int first = -1;
      for (int b : incident[start])
        if (!used[b] && directed[b][0] == start) {
          first = b;
          break;
        }
      if (first < 0)
        for (int b : incident[start])
          if (!used[b]) {
            first = b;
            break;
          }
      if (first < 0) break;
      std::vector<int> loop{start};
      int edge = first, current = start;
      while (true) {
        used[edge] = 1;
        const int next = directed[edge][0] == current ? directed[edge][1] : directed[edge][0];
        if (next == start) break;
        loop.push_back(next);
        current = next;
        edge = -1;
        for (int b : incident[current])
          if (!used[b]) {
            edge = b;
            break;
          }
        if (edge < 0) break;  // open chain (should not happen on a valid mesh)
      }
      loops.push_back(std::move(loop));
    }
  }
  return loops;
}

std::vector<std::vector<int>> vertexAdjacency(const Eigen::MatrixXi& F, int num_vertices) {
  std::vector<std::vector<int>> adjacency(std::max(num_vertices, 0));
  const Eigen::MatrixXi E = uniqueEdges(F);
  for (int e = 0; e < E.rows(); ++e) {
    if (E(e, 1) >= num_vertices) continue;
    adjacency[E(e, 0)].push_back(E(e, 1));
    adjacency[E(e, 1)].push_back(E(e, 0));
  }
  for (auto& list : adjacency) std::sort(list.begin(), list.end());
  return adjacency;
}

std::vector<std::vector<int>> vertexFaces(const Eigen::MatrixXi& F, int num_vertices) {
  std::vector<std::vector<int>> faces(std::max(num_vertices, 0));
  for (int f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      if (F(f, c) < num_vertices) faces[F(f, c)].push_back(f);
  return faces;  // already ascending: faces are visited in order
}

namespace {

// Face adjacency through manifold edges: for each face and corner, the neighbouring face
// across the edge opposite that corner (-1 if none).
Eigen::MatrixXi faceNeighbours(const Eigen::MatrixXi& F) {
  Eigen::MatrixXi E, EF, EI;
  edgeFlaps(F, E, EF, EI);
  Eigen::MatrixXi N = Eigen::MatrixXi::Constant(F.rows(), 3, -1);
  for (int e = 0; e < E.rows(); ++e) {
    if (EF(e, 1) < 0) continue;
    N(EF(e, 0), EI(e, 0)) = EF(e, 1);
    N(EF(e, 1), EI(e, 1)) = EF(e, 0);
  }
  return N;
}

// True if faces f and g traverse their shared edge in opposite directions (consistent
// winding), or share no edge.
bool consistentWinding(const Eigen::MatrixXi& F, int f, int g) {
  for (int a = 0; a < 3; ++a) {
    const int u = F(f, a), v = F(f, (a + 1) % 3);
    for (int b = 0; b < 3; ++b) {
      if (F(g, b) == v && F(g, (b + 1) % 3) == u) return true;
      if (F(g, b) == u && F(g, (b + 1) % 3) == v) return false;
    }
  }
  return true;
}

}  // namespace

Eigen::VectorXi faceComponents(const Eigen::MatrixXi& F) {
  const Eigen::MatrixXi N = faceNeighbours(F);
  Eigen::VectorXi C = Eigen::VectorXi::Constant(F.rows(), -1);
  int next_id = 0;
  for (int seed = 0; seed < F.rows(); ++seed) {
    if (C(seed) >= 0) continue;
    std::queue<int> queue;
    queue.push(seed);
    C(seed) = next_id;
    while (!queue.empty()) {
      const int f = queue.front();
      queue.pop();
      for (int c = 0; c < 3; ++c) {
        const int g = N(f, c);
        if (g >= 0 && C(g) < 0) {
          C(g) = next_id;
          queue.push(g);
        }
      }
    }
    ++next_id;
  }
  return C;
}

Eigen::VectorXi vertexComponents(const Eigen::MatrixXi& F, int num_vertices) {
  // Union-find with path halving (Tarjan 1975).
  std::vector<int> parent(num_vertices);
  for (int v = 0; v < num_vertices; ++v) parent[v] = v;
  auto root = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 1; k < 3; ++k) parent[root(F(f, k))] = root(F(f, 0));
  Eigen::VectorXi C(num_vertices);
  std::vector<int> id_of_root(num_vertices, -1);
  int next_id = 0;
  for (int v = 0; v < num_vertices; ++v) {
    int& id = id_of_root[root(v)];
    if (id < 0) id = next_id++;
    C(v) = id;
  }
  return C;
}

bool orientFacesConsistently(const Eigen::MatrixXi& F, Eigen::MatrixXi& out) {
  out = F;
  const Eigen::MatrixXi N = faceNeighbours(F);
  std::vector<char> visited(F.rows(), 0);
  for (int seed = 0; seed < F.rows(); ++seed) {
    if (visited[seed]) continue;
    std::queue<int> queue;
    queue.push(seed);
    visited[seed] = 1;
    while (!queue.empty()) {
      const int f = queue.front();
      queue.pop();
      for (int c = 0; c < 3; ++c) {
        const int g = N(f, c);
        if (g < 0 || visited[g]) continue;
        if (!consistentWinding(out, f, g)) std::swap(out(g, 1), out(g, 2));
        visited[g] = 1;
        queue.push(g);
      }
    }
  }
  // Verify every manifold edge.
  for (int f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      if (N(f, c) >= 0 && !consistentWinding(out, f, N(f, c))) return false;
  return true;
}

}  // namespace chordfit
