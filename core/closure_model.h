// A case's closure as a simulation problem: closureModel builds the SimulationModel of a
// ValveCase and its CordSet (boundary, tips, cords, flow direction), simulateClosure runs it
// (simulator.h).
#pragma once

#include <string>

#include "core/case_data.h"
#include "core/cordset.h"
#include "core/simulator.h"

namespace chordfit {

// The model of a case's closure (phase kClose) or opening (kOpen):
//   - F consistently oriented; per connected component the winding normal is chosen to point
//     to the atrial side (toward n_AP and toward the valve axis; DESIGN §4);
//   - fixed = mesh.annulus, open positions mesh.V, closed positions case.annulus_closed
//     (static at the open positions if annulus_closed is empty);
//   - tips from `cords.tips` (closed_position when given, else static);
//   - flow_direction = n_AP of openAnnulusFrame (toward the atrium); reversed for kOpen.
// Returns false and sets `error` on inconsistent input (indices out of range, sizes).
bool closureModel(const ValveCase& valve_case, const CordSet& cords, ClosurePhase phase,
                  SimulationModel& model, std::string& error);

// closureModel + simulate. For phase kOpen a warm start (the closed state) is required.
SimulationResult simulateClosure(const ValveCase& valve_case, const CordSet& cords,
                                 const SimulationSettings& settings,
                                 const Eigen::MatrixXd* warm_start = nullptr);

}  // namespace chordfit
