// Determinism of the closure (issue 3: same input => identical bytes, whatever the threads).
// Two ways threads enter: the caller's (the fit runs closures in parallel), where shared state
// between runs or a dependence on the calling thread would break it, and the closure's own
// (SimulationSettings::threads: colour classes and contact detection split between threads,
// simulator.h), which must give the bytes of the single-threaded closure.
#include <cstring>
#include <thread>

#include <gtest/gtest.h>

#include "core/closure_model.h"
#include "core/heuristic.h"
#include "core/mesh_io.h"
#include "core/parametric_valve.h"
#include "tests/test_coarse_valve.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

using testing::CoarseValve;

// The closed state as written to closed.ply, and the raw doubles (the PLY stores floats, so
// the doubles are the stricter comparison).
struct ClosedState {
  std::string ply;
  Eigen::MatrixXd V;
  bool operator==(const ClosedState& o) const {
    return ply == o.ply && V.size() == o.V.size() &&
           std::memcmp(V.data(), o.V.data(), sizeof(double) * V.size()) == 0;
  }
};

ClosedState close(const CoarseValve& c, const testing::TempDir& dir, const std::string& name) {
  const SimulationResult r = simulateClosure(c.valve.valve_case, c.cords, SimulationSettings{});
  EXPECT_TRUE(r.ok()) << r.error;
  EXPECT_TRUE(r.converged);
  if (!r.ok()) return {};
  writePly(dir / name, r.V, c.valve.valve_case.mesh.F);
  return {testing::readText(dir / name), r.V};
}

TEST(SimulatorDeterminism, ClosedPlyIsBitIdenticalForSequentialAndConcurrentRuns) {
  const CoarseValve valve;
  const testing::TempDir dir;
  const ClosedState first = close(valve, dir, "first.ply");
  const ClosedState second = close(valve, dir, "second.ply");
  ClosedState concurrent[2];
  std::thread a([&] { concurrent[0] = close(valve, dir, "thread_a.ply"); });
  std::thread b([&] { concurrent[1] = close(valve, dir, "thread_b.ply"); });
  a.join();
  b.join();
  ASSERT_FALSE(first.ply.empty());
  EXPECT_TRUE(first == second);
  EXPECT_TRUE(first == concurrent[0]);
  EXPECT_TRUE(first == concurrent[1]);
}

TEST(SimulatorDeterminism, WarmStartedRunsAreBitIdentical) {
  // The inverse fit re-runs from a base closed state thousands of times: the warm-started map
  // must be as reproducible as the cold one.
  const CoarseValve valve;
  const SimulationResult base =
      simulateClosure(valve.valve.valve_case, valve.cords, SimulationSettings{});
  ASSERT_TRUE(base.ok()) << base.error;
  CordSet scaled = valve.cords;
  scaled.cords[0].rest_length *= 0.99;
  SimulationResult runs[2];
  std::thread a([&] {
    runs[0] = simulateClosure(valve.valve.valve_case, scaled, SimulationSettings{}, &base.V);
  });
  runs[1] = simulateClosure(valve.valve.valve_case, scaled, SimulationSettings{}, &base.V);
  a.join();
  ASSERT_TRUE(runs[0].ok() && runs[1].ok());
  ASSERT_EQ(runs[0].V.size(), runs[1].V.size());
  EXPECT_EQ(std::memcmp(runs[0].V.data(), runs[1].V.data(), sizeof(double) * runs[0].V.size()), 0);
  EXPECT_EQ(runs[0].steps, runs[1].steps);
}

// A valve fine enough that its colour classes are split between the threads (classes of at
// least 128 constraints; ~500 vertices, edge 1.65 mm) and its contact detection too.
SimulationResult closeWithThreads(const ParametricValve& valve, const CordSet& cords, int threads,
                                  bool edge_contact, const Eigen::MatrixXd* start = nullptr) {
  SimulationSettings settings;
  settings.threads = threads;
  settings.edge_contact = edge_contact;
  return simulateClosure(valve.valve_case, cords, settings, start);
}

bool sameBytes(const SimulationResult& a, const SimulationResult& b) {
  return a.V.size() == b.V.size() && a.steps == b.steps &&
         std::memcmp(a.V.data(), b.V.data(), sizeof(double) * a.V.size()) == 0;
}

TEST(SimulatorDeterminism, TwoSimulatorThreadsGiveTheBytesOfOne) {
  ValveParameters parameters;
  parameters.target_edge_mm = 1.65;
  const ParametricValve valve = makeParametricValve(parameters);
  const CordSet cords = heuristicCordSet(valve.valve_case);
  for (const bool edge_contact : {false, true}) {
    SCOPED_TRACE(edge_contact ? "vertex and edge contact" : "vertex contact");
    const SimulationResult one = closeWithThreads(valve, cords, 1, edge_contact);
    const SimulationResult two = closeWithThreads(valve, cords, 2, edge_contact);
    ASSERT_TRUE(one.ok() && two.ok()) << one.error << two.error;
    // Two threads that fell back to one would compare one thread with itself.
    EXPECT_FALSE(two.threads_gave_up);
    EXPECT_TRUE(one.converged);
    EXPECT_GT(one.contact_rebuilds, 1);
    EXPECT_TRUE(sameBytes(one, two));
    // A warm start from the closed state, as the fit's finite differences run.
    CordSet scaled = cords;
    scaled.cords[0].rest_length *= 0.99;
    const SimulationResult warm_one = closeWithThreads(valve, scaled, 1, edge_contact, &one.V);
    const SimulationResult warm_two = closeWithThreads(valve, scaled, 2, edge_contact, &one.V);
    ASSERT_TRUE(warm_one.ok() && warm_two.ok());
    EXPECT_TRUE(sameBytes(warm_one, warm_two));
  }
}

}  // namespace
}  // namespace chordfit
