// A coarse parametric valve with its heuristic cords: the closure tests' fast valve that still
// closes like a real one.
#pragma once

#include <Eigen/Core>

#include "core/closure_model.h"
#include "core/heuristic.h"
#include "core/parametric_valve.h"

namespace chordfit::testing {

constexpr double kCoarseEdgeMm = 3.0;  // ~180 vertices: fast, but leaflets still coapt

struct CoarseValve {
  ParametricValve valve;
  CordSet cords;
  CoarseValve() {
    ValveParameters parameters;
    parameters.target_edge_mm = kCoarseEdgeMm;
    valve = makeParametricValve(parameters);
    cords = heuristicCordSet(valve.valve_case);
  }
  SimulationResult close(const SimulationSettings& settings,
                         const Eigen::MatrixXd* start = nullptr) const {
    return simulateClosure(valve.valve_case, cords, settings, start);
  }
};

}  // namespace chordfit::testing
