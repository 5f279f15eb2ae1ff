// Do the leaflet labels and the tracings agree? Each tracing names its leaflet, each mesh
// vertex has a label; on a correctly labelled valve most traced points of the closed valve
// lie nearest an open-state vertex of their own leaflet. Swapped labels (1 - label in
// leaflets.json) or landmarks in another frame pass every other check, and the fit then
// measures each point to the wrong leaflet (a fit of the small bundled case ended at AvgD
// 2.23 instead of 0.42 mm).
#pragma once

#include <vector>

#include "core/case_data.h"
#include "core/valve_mesh.h"

namespace chordfit {

// The share of the leaflet-labelled tracing points whose nearest open-state vertex carries
// their leaflet's label, or NaN without such points.
double tracingLeafletAgreement(const ValveMesh& mesh, const std::vector<Tracing>& tracings);

// Below this share the labels and the tracings disagree: 65-80 % on correctly labelled
// valves, the cohort's included (docs/case-format.md, "Leaflet labels").
constexpr double kLeafletAgreementLow = 0.5;

}  // namespace chordfit
