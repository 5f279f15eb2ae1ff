// Flat test sheets for the simulator's known-answer tests: a disc (membrane, plate, cord and
// determinism tests) and an equilateral triangle lattice (plate strip, uniaxial stretch).
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "core/simulator.h"

namespace chordfit::testing {

// Flat disc of radius a in the plane z = 0: a centre vertex (index 0) and `rings` concentric
// rings of 6k vertices (k = 1..rings), ring k starting at index 1 + 3k(k-1) with its vertex at
// angle 0. Triangles are wound counter-clockwise seen from +z (winding normal +z, so a
// pressure pushes the disc toward +z). `boundary` = the outermost ring.
inline void makeDisc(double a, int rings, Eigen::MatrixXd& V, Eigen::MatrixXi& F,
                     Eigen::VectorXi& boundary) {
  std::vector<Eigen::Vector3d> points{Eigen::Vector3d::Zero()};
  std::vector<std::vector<int>> ring_ids{{0}};
  for (int k = 1; k <= rings; ++k) {
    std::vector<int> ids;
    const int count = 6 * k;
    for (int m = 0; m < count; ++m) {
      const double phi = 2.0 * M_PI * m / count;
      ids.push_back(static_cast<int>(points.size()));
      points.emplace_back(a * k / rings * std::cos(phi), a * k / rings * std::sin(phi), 0.0);
    }
    ring_ids.push_back(ids);
  }
  std::vector<Eigen::Vector3i> faces;
  // Zip consecutive rings by angle: advance on whichever ring's next vertex comes first.
  for (int k = 1; k <= rings; ++k) {
    const std::vector<int>& in = ring_ids[k - 1];
    const std::vector<int>& out = ring_ids[k];
    const int ni = static_cast<int>(in.size()), no = static_cast<int>(out.size());
    int i = 0, o = 0;
    while (o < no || (ni > 1 && i < ni)) {
      const double next_in = ni == 1 ? 1e9 : static_cast<double>(i + 1) / ni;
      const double next_out = static_cast<double>(o + 1) / no;
      if (next_out <= next_in && o < no) {
        faces.emplace_back(in[i % ni], out[o], out[(o + 1) % no]);
        ++o;
      } else {
        faces.emplace_back(in[i % ni], out[o % no], in[(i + 1) % ni]);
        ++i;
      }
    }
  }
  V.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t p = 0; p < points.size(); ++p) V.row(p) = points[p].transpose();
  F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) F.row(f) = faces[f].transpose();
  boundary = Eigen::Map<const Eigen::VectorXi>(ring_ids.back().data(),
                                               static_cast<Eigen::Index>(ring_ids.back().size()));
}

// An equilateral triangle lattice in z = 0 with edge `edge`: `rows` + 1 rows along x at
// y = 0, h, 2h, ... (h = sqrt(3)/2 edge), `columns` vertices each, odd rows shifted by half an
// edge. Vertex (r, c) has index r * columns + c; triangles wound counter-clockwise seen from +z.
inline void makeTriangleLattice(int columns, int rows, double edge, Eigen::MatrixXd& V,
                                Eigen::MatrixXi& F) {
  const double h = 0.5 * std::sqrt(3.0) * edge;
  V.resize(static_cast<Eigen::Index>(rows + 1) * columns, 3);
  auto id = [columns](int r, int c) { return r * columns + c; };
  for (int r = 0; r <= rows; ++r)
    for (int c = 0; c < columns; ++c) V.row(id(r, c)) << (c + 0.5 * (r % 2)) * edge, r * h, 0.0;
  std::vector<Eigen::Vector3i> faces;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c + 1 < columns; ++c) {
      if (r % 2 == 0) {
        faces.emplace_back(id(r, c), id(r, c + 1), id(r + 1, c));
        faces.emplace_back(id(r, c + 1), id(r + 1, c + 1), id(r + 1, c));
      } else {
        faces.emplace_back(id(r, c), id(r + 1, c + 1), id(r + 1, c));
        faces.emplace_back(id(r, c), id(r, c + 1), id(r + 1, c + 1));
      }
    }
  F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) F.row(f) = faces[f].transpose();
}

// Holds `fixed` at their rest positions (moving to `end` over the ramp when given), one PM
// tip at `tip` that never moves, no cords.
inline void holdVertices(SimulationModel& model, const std::vector<int>& fixed,
                         const Eigen::MatrixXd* end = nullptr,
                         const Eigen::Vector3d& tip = Eigen::Vector3d(0, 0, -10)) {
  model.fixed =
      Eigen::Map<const Eigen::VectorXi>(fixed.data(), static_cast<Eigen::Index>(fixed.size()));
  model.fixed_start.resize(model.fixed.size(), 3);
  for (Eigen::Index k = 0; k < model.fixed.size(); ++k)
    model.fixed_start.row(k) = model.V_rest.row(model.fixed(k));
  model.fixed_end = end ? *end : model.fixed_start;
  model.tip_start = tip.transpose();
  model.tip_end = model.tip_start;
}

// Index of the vertex of ring k at angle 0.
inline int discRingStart(int k) { return k == 0 ? 0 : 1 + 3 * k * (k - 1); }

// A clamped disc model (boundary fixed in place), one PM tip at `tip`, no cords.
inline SimulationModel clampedDiscModel(double radius, int rings,
                                        const Eigen::Vector3d& tip = Eigen::Vector3d(0, 0, -10)) {
  SimulationModel model;
  Eigen::VectorXi boundary;
  makeDisc(radius, rings, model.V_rest, model.F, boundary);
  holdVertices(model, std::vector<int>(boundary.data(), boundary.data() + boundary.size()), nullptr,
               tip);
  return model;
}

}  // namespace chordfit::testing
