// Combinatorial structure of a triangle mesh, as free functions on F (libigl style).
// Nothing here looks at vertex positions. Every result is deterministic: it depends only on F,
// never on hash order or thread count.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace chordfit {

// Undirected edges of F, each once.
//   F  #F by 3 triangle vertex indices (non-negative)
// Returns E  #E by 2, E(e,0) < E(e,1), rows sorted lexicographically.
Eigen::MatrixXi uniqueEdges(const Eigen::MatrixXi& F);

// Edge-face incidence ("edge flaps", cf. igl::edge_flaps).
//   F   #F by 3
//   E   #E by 2 output, = uniqueEdges(F)
//   EF  #E by 2 output, the faces incident to each edge in increasing face order;
//       EF(e,1) = -1 on boundary edges. A non-manifold edge (> 2 faces) keeps its first two
//       faces; nonManifoldEdgeCount tells whether that happened.
//   EI  #E by 2 output, EI(e,s) in {0,1,2}: the corner of face EF(e,s) opposite edge e
//       (-1 where EF is -1).
void edgeFlaps(const Eigen::MatrixXi& F, Eigen::MatrixXi& E, Eigen::MatrixXi& EF,
               Eigen::MatrixXi& EI);

// Number of edges shared by more than two faces.
int nonManifoldEdgeCount(const Eigen::MatrixXi& F);

// Interior-edge "flaps" for dihedral bending: one row (i, j, k, l) per edge shared by exactly
// two faces, where (i, j) is the edge with i -> j in the winding of the first face, k is the
// vertex of the first face opposite the edge and l the vertex of the second face opposite it.
// Rows follow the order of uniqueEdges(F).
//   F  #F by 3
// Returns Q  #B by 4.
Eigen::MatrixXi bendingQuads(const Eigen::MatrixXi& F);

// Boundary loops (edges with exactly one incident face), each an ordered, closed vertex loop
// (last vertex connects back to the first; the first is not repeated). Each loop starts at its
// smallest vertex index and follows the boundary edge out of that vertex in the winding of its
// face. Loops are returned in increasing order of their start vertex. Works for
// inconsistently oriented faces too (walks the undirected boundary graph).
//   F  #F by 3
std::vector<std::vector<int>> boundaryLoops(const Eigen::MatrixXi& F);

// Boundary loops of a valve surface beyond the two it is made of, the annulus ring and the
// leaflets' free edge: holes or loose pieces (0 when there are two or fewer).
//   loop_count  boundaryLoops(F).size()
inline int holesBeyondRingAndFreeEdge(std::size_t loop_count) {
  return loop_count > 2 ? static_cast<int>(loop_count) - 2 : 0;
}

// Neighbouring vertices of every vertex through an edge, each list sorted ascending.
//   F             #F by 3
//   num_vertices  #V (isolated vertices get an empty list)
std::vector<std::vector<int>> vertexAdjacency(const Eigen::MatrixXi& F, int num_vertices);

// Faces incident to every vertex, each list sorted ascending.
std::vector<std::vector<int>> vertexFaces(const Eigen::MatrixXi& F, int num_vertices);

// Connected components of faces through shared edges.
//   F  #F by 3
// Returns C  #F component id per face, ids 0.. in order of the smallest face of each
// component.
Eigen::VectorXi faceComponents(const Eigen::MatrixXi& F);

// Connected components of vertices through faces: a face joins its three vertices, so pieces
// that touch at a single vertex (a bowtie) are one component, unlike faceComponents.
//   F  #F by 3, num_vertices  #V (a vertex in no face is a component of its own)
// Returns #V component id per vertex, ids 0.. in order of the smallest vertex of each
// component.
Eigen::VectorXi vertexComponents(const Eigen::MatrixXi& F, int num_vertices);

// Consistent orientation: flips faces so that within each edge-connected component every
// interior edge is traversed in opposite directions by its two faces. In each component the
// face with the smallest index keeps its winding. Returns false if some component is not
// orientable (e.g. a Moebius strip); the result is then consistent on a spanning tree only.
//   F    #F by 3
//   out  #F by 3 output (may alias nothing; F is not modified)
bool orientFacesConsistently(const Eigen::MatrixXi& F, Eigen::MatrixXi& out);

}  // namespace chordfit
