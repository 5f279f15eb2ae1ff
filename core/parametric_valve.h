// Parametric mitral valve in the open (diastolic) state, with a contracted, deeper-saddled
// closed-state (systolic) annulus. Anatomical defaults are from published human data; see
// parametric_valve.cpp for the sources.
//
// Frame: z = annulus-plane normal toward the atrium, x = anteroposterior axis with the
// anterior leaflet at +x, y = commissural axis with the anterolateral commissure at +y
// (matches AnnulusFrame: n = z, a = x, l = n x a = y).
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"

namespace chordfit {

struct ValveParameters {
  double ap_diameter_mm = 28.0;            // anteroposterior (septal-lateral) diameter, open
  double cc_diameter_mm = 35.0;            // commissure-commissure diameter, open
  double saddle_height_mm = 5.0;           // annular height (peak to trough), open
  double closed_contraction = 0.9;         // closed/open ratio of in-plane annulus dimensions
  double closed_saddle_height_mm = 7.0;    // deeper saddle in systole
  double anterior_fraction = 1.0 / 3.0;    // share of the annulus circumference (anterior)
  double anterior_height_mm = 23.0;        // A2 height, annulus to free edge
  double posterior_height_mm = 14.0;       // P2 height
  double posterior_side_height_mm = 11.0;  // P1 / P3 heights
  double commissural_height_mm = 8.0;      // leaflet height at the commissures
  // Fraction of the scallop height lost at the P1/P2 and P2/P3 clefts (the indentations that
  // let the posterior leaflet unfold; Carpentier). 0.8 rather than 0.5: with the shallower
  // clefts the scallops are tied together so tightly that elongated P2 cords (x 1.3) lift P1
  // and P3 over the prolapse criterion as well, where isolated P2 prolapse is the commonest
  // degenerative lesion; at 0.8 P2 prolapses alone at edges 1.5-3 mm and the normal cords
  // prolapse nowhere (experiments/README.md "Calibration"; docs/performance.md, "Clefts of the
  // normal anatomy").
  double indentation_depth = 0.8;
  double target_edge_mm = 1.5;  // mesh resolution
  // Optional user annulus (#P by 3, ordered, closed loop implied) replacing the parametric
  // ellipse/saddle for the open state. The closed annulus is derived from it by contraction
  // about its centroid and saddle deepening. Its bounding-box diagonal must lie within the
  // limits below.
  std::optional<Eigen::MatrixXd> annulus_polyline;
};

// A user annulus's span (bounding-box diagonal), mm: the ellipse's limits (ap and cc up to
// 100 mm, a saddle up to half of that: sqrt(100^2 + 100^2 + 50^2) = 150) and the smallest
// valve mesh a case may hold (2 mm); metres (~0.05) and micrometres (~4e4) fall outside.
constexpr double kMinAnnulusSpanMm = 2.0;
constexpr double kMaxAnnulusSpanMm = 150.0;

struct ParametricValve {
  ValveCase valve_case;       // mesh (open), labels, annulus ring, closed annulus; no tracings
  Eigen::VectorXi segment;    // #V Carpentier segment id = leaflet * 3 + (0..2)
  Eigen::VectorXi free_edge;  // ordered loop of free-edge vertex indices
  // Per annulus column (mesh.annulus(k) .. free_edge(k)): its position along its leaflet's
  // arc, 0 at the anterolateral commissure, 1 at the posteromedial one, as the polar angle
  // between the commissures of the annulus curve (not of the mesh ring), so the same on
  // meshes of any resolution.
  Eigen::VectorXd column_fraction;
};

// Builds the valve. Throws std::invalid_argument naming the parameter if one is out of range.
ParametricValve makeParametricValve(const ValveParameters& parameters);

}  // namespace chordfit
