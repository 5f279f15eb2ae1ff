// A case: the open-state valve, its closed annulus, tracings of the closed valve, and
// optional PM tips, cords and simulation overrides. On disk a case is a directory with
// case.json (docs/case-format.md); case_io.h reads and writes it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/cordset.h"
#include "core/valve_mesh.h"

namespace chordfit {

// One tracing: a polyline of the closed valve drawn on one image plane.
struct Tracing {
  Eigen::MatrixXd points;  // #P by 3, mm, #P >= 2
  Eigen::Vector3d plane_origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d plane_normal = Eigen::Vector3d::UnitZ();  // unit
  int leaflet = -1;  // leaflet label, or -1 when the reader did not say
};

struct ValveCase {
  std::string name;
  ValveMesh mesh;                  // open state
  Eigen::MatrixXd annulus_closed;  // #ring by 3 closed-state positions of mesh.annulus
  std::vector<Tracing> tracings;
  std::optional<std::vector<PmTip>> tips;  // optional PM tips (else heuristic)
  std::optional<CordSet> cords;            // optional cords (else automatic + heuristic)
  std::string simulation_json = "{}";      // optional simulator overrides, raw JSON object
  // Optional regional tissue: one stiffness factor > 0 per mesh vertex on the case's leaflet
  // material (empty = uniform; SimulationModel::tissue_stiffness). Synthetic truths use it for
  // the softer tissue of a myxomatous lesion (cohort_presets.h).
  Eigen::VectorXd tissue_stiffness;
};

}  // namespace chordfit
