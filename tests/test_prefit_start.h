// The start the pre-fit tests share: the bundled small-normal case with uniform cords, and the
// noise-free tracings of a closure a test makes its truth.
#pragma once

#include <stdexcept>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"
#include "core/closure_model.h"
#include "core/cohort_presets.h"
#include "core/metrics.h"
#include "core/simulator.h"
#include "tests/test_support.h"

namespace chordfit::testing {

struct PrefitStart {
  ValveCase valve_case;  // the bundled case; a test replaces its tracings by its truth's
  SimulationSettings settings;
  CordSet base;                    // every cord at the same scale of its seed length
  Eigen::VectorXi vertex_segment;  // each vertex's open-state mitral segment
  int p2 = -1;                     // segment id of P2
};

// The bundled small-normal case with every cord at `cord_scale` times its seed rest length.
inline PrefitStart smallNormalPrefitStart(double cord_scale) {
  PrefitStart p;
  BundledCase bundled = bundledCase("small-normal");
  p.valve_case = bundled.valve_case;
  p.settings = bundled.settings;
  p.vertex_segment = openStateSegments(p.valve_case.mesh);
  p.p2 = mitralSegmentId("P2");  // the bundled case's leaflets: anterior, posterior
  p.base = *p.valve_case.cords;
  for (Cord& cord : p.base.cords) cord.rest_length = cord.seed_rest_length * cord_scale;
  return p;
}

// Noise-free tracings on `planes` planes of `truth` closed on `truth_cords`: what a fit that
// finds the truth reproduces exactly. Throws when the closure fails.
inline std::vector<Tracing> tracingsOfTruth(const ValveCase& truth, const CordSet& truth_cords,
                                            const SimulationSettings& settings, int planes) {
  const SimulationResult closed = simulateClosure(truth, truth_cords, settings);
  if (!closed.ok()) throw std::runtime_error(closed.error);
  return noiseFreeTracings(truth, closed.V, planes);
}

}  // namespace chordfit::testing
