// prolapseOfSections (core/metrics.h): the closed mesh cut by the tracing planes and localised
// like the tracing points. On noise-free, gap-free tracings of the same closed mesh it must
// report exactly the tracings' segments, whatever the tissue-based measure says.
#include <gtest/gtest.h>

#include <filesystem>

#include <Eigen/Geometry>

#include "core/case_io.h"
#include "core/closure_model.h"
#include "core/metrics.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

TEST(SectionProlapse, MatchesNoiseFreeTracingsOfTheSameMesh) {
  Diagnostics diagnostics;
  auto loaded = loadCase(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal", diagnostics);
  ASSERT_TRUE(loaded && loaded->cords);
  ValveCase valve_case = *loaded;
  const SimulationSettings settings = settingsFromJson(valve_case.simulation_json, diagnostics);
  // Every cord slack but the anterior ones: the posterior leaflet rises, so there is a
  // prolapse to localise.
  CordSet cords = *valve_case.cords;
  for (Cord& cord : cords.cords) {
    const bool anterior = valve_case.mesh.leaflet(cord.vertex) == 0;
    cord.rest_length = cord.seed_rest_length * (anterior ? 0.8 : 1.5);
  }
  const SimulationResult closed = simulateClosure(valve_case, cords, settings);
  ASSERT_TRUE(closed.ok()) << closed.error;

  valve_case.tracings = testing::noiseFreeTracings(valve_case, closed.V, 6);
  const ValveMetrics metrics = computeMetrics(valve_case, closed.V);
  EXPECT_FALSE(metrics.tracing_prolapse.segments.empty()) << "the case must prolapse somewhere";
  EXPECT_EQ(metrics.section_prolapse.segments, metrics.tracing_prolapse.segments);
  EXPECT_TRUE(metrics.prolapse_reconstructed) << "Table 1's criterion is the like-for-like one";
}

TEST(SectionProlapse, CutsEachImagePlaneOnceWhateverOriginOrNormalSignItsPolylinesCarry) {
  const testing::TracedSeedClosure seed = testing::tracedSeedClosure("small-normal", 3);
  ValveCase varied = seed.traced;
  // Each polyline again, with its origin moved within its plane and its normal reversed: the
  // same image planes, as a reader's file may give them.
  for (const Tracing& t : seed.traced.tracings) {
    Tracing again = t;
    again.plane_origin += 3.0 * t.plane_normal.unitOrthogonal();
    again.plane_normal = -t.plane_normal;
    varied.tracings.push_back(again);
  }
  const ClosedAnnulus annulus = closedAnnulus(seed.traced);
  const ProlapseResult once = prolapseOfSections(seed.traced, annulus, seed.closed_V);
  const ProlapseResult twice = prolapseOfSections(varied, annulus, seed.closed_V);
  EXPECT_EQ(twice.heights.size(), once.heights.size()) << "no plane cut twice";
  EXPECT_EQ(twice.segments, once.segments);
}

TEST(SectionProlapse, NoTracingsNoSections) {
  Diagnostics diagnostics;
  auto loaded = loadCase(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal", diagnostics);
  ASSERT_TRUE(loaded);
  ValveCase valve_case = *loaded;
  valve_case.tracings.clear();
  const ProlapseResult result =
      prolapseOfSections(valve_case, closedAnnulus(valve_case), valve_case.mesh.V);
  EXPECT_TRUE(result.segments.empty());
}

}  // namespace
}  // namespace chordfit
