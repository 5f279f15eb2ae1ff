#include <iostream>
#include <stdexcept>

#include "core/case_io.h"
#include "core/curve_io.h"
#include "core/parametric_valve.h"
#include "tools/command_support.h"
#include "tools/commands.h"

namespace chordfit::cli {

int runMakeValve(const MakeValveOptions& options) {
  ValveParameters parameters;
  parameters.target_edge_mm = options.edge_mm;
  if (!options.annulus_file.empty()) {
    Diagnostics diagnostics;
    Curve curve;
    if (!readCurve(options.annulus_file, curve, diagnostics, options.annulus_file)) {
      return reportProblems(diagnostics);
    }
    parameters.annulus_polyline = curve.points;
  }
  ParametricValve valve;
  try {
    valve = makeParametricValve(parameters);
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: " << (options.annulus_file.empty() ? "make-valve" : options.annulus_file)
              << ": parameters: " << e.what() << "\n";
    return kExitBadInput;
  }
  valve.valve_case.name = options.name;
  writeCase(options.out_dir, valve.valve_case);
  std::cout << "wrote " << options.out_dir << "/case.json\n" << caseSummary(valve.valve_case);
  return kExitOk;
}

}  // namespace chordfit::cli
