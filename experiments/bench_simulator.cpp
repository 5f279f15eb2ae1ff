// Benchmarks of the XPBD closure simulator (DESIGN §4 performance targets):
//   - BM_CloseParametricValve: closes the parametric normal valve with the heuristic cords at
//     ~500, ~2,000 and ~8,000 vertices; reports wall time, thread CPU time, steps,
//     convergence and the average cost of one constraint projection (the whole loop,
//     prediction and contact detection included, divided by the projection count).
//   - BM_Projection<Kind>: one Gauss-Seidel sweep of one constraint kind on the open
//     ~2,000-vertex valve: the raw kernel cost, ns per projection.
// Run: build/experiments/bench_simulator [--benchmark_filter=...]
// BM_CloseParametricValveTwoThreads: the same closures with SimulationSettings::threads = 2.
// The machine's other load shows in wall time, so compare cpu_s too (single-threaded rows).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <vector>

#include "core/closure_model.h"
#include "core/contact.h"
#include "core/heuristic.h"
#include "core/mesh_topology.h"
#include "core/parametric_valve.h"
#include "core/xpbd_constraints.h"

namespace chordfit {
namespace {

// Parametric valve resolution (target edge, mm) per benchmark argument; the vertex counts
// are reported as a counter (506, 1,996 and 8,122 since the normal anatomy's deeper clefts of
// 2026-11-25; 494, 2,092 and 8,071 at edges 1.7, 0.8 and 0.4 before).
double targetEdge(int64_t size_class) {
  switch (size_class) {
    case 0:
      return 1.65;  // ~500 vertices
    case 1:
      return 0.8;  // ~2,000
    default:
      return 0.39;  // ~8,000
  }
}

// Closes the valve of size class `size_class` with `threads` threads (SimulationSettings::
// threads) and reports the counters.
void closeParametricValve(benchmark::State& state, int64_t size_class, int threads) {
  ValveParameters parameters;
  parameters.target_edge_mm = targetEdge(size_class);
  const ParametricValve valve = makeParametricValve(parameters);
  const CordSet cords = heuristicCordSet(valve.valve_case);
  SimulationResult result;
  for (auto _ : state) {
    SimulationSettings settings;
    settings.max_steps = 20000;  // the finest valve needs more than the default cap
    settings.threads = threads;
    result = simulateClosure(valve.valve_case, cords, settings);
    benchmark::DoNotOptimize(result.V.data());
  }
  if (!result.ok()) {
    state.SkipWithError(result.error.c_str());
    return;
  }
  state.counters["vertices"] = static_cast<double>(valve.valve_case.mesh.V.rows());
  state.counters["steps"] = result.steps;
  state.counters["converged"] = result.converged ? 1 : 0;
  state.counters["wall_s"] = result.seconds;
  state.counters["cpu_s"] = result.cpu_seconds;  // the calling thread's CPU time
  // Per projection: CPU time single-threaded (the target), wall time with threads.
  const double seconds = threads > 1 ? result.seconds : result.cpu_seconds;
  state.counters["ns_per_proj"] = 1e9 * seconds / static_cast<double>(result.projections);
  state.counters["ms_per_step"] = 1e3 * seconds / result.steps;
  state.counters["contact_rebuilds"] = result.contact_rebuilds;
  state.counters["dt_ms"] = result.dt_ms;
  if (threads > 1) state.counters["gave_up"] = result.threads_gave_up ? 1 : 0;
}

// The three sizes, one closure each (a closure is seconds to a minute, and deterministic).
void closureRows(benchmark::internal::Benchmark* b) {
  b->Arg(0)->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
}

void BM_CloseParametricValve(benchmark::State& state) {
  closeParametricValve(state, state.range(0), 1);
}
BENCHMARK(BM_CloseParametricValve)->Apply(closureRows);

// The same closures with the material sweeps split between two threads (bit-identical
// results; the machine's two cores).
void BM_CloseParametricValveTwoThreads(benchmark::State& state) {
  closeParametricValve(state, state.range(0), 2);
}
BENCHMARK(BM_CloseParametricValveTwoThreads)->Apply(closureRows);

// Constraint arrays of the open ~2,000-vertex valve, built as the simulator does (compliances
// do not change the cost; positions are perturbed so every projection does work).
struct KernelFixture {
  std::vector<double> x, w;
  std::vector<DistanceConstraint> edges;
  std::vector<AreaConstraint> areas;
  std::vector<BendingConstraint> bends;
  std::vector<ContactConstraint> contacts;
  KernelFixture() {
    ValveParameters parameters;
    parameters.target_edge_mm = targetEdge(1);
    const ValveMesh mesh = makeParametricValve(parameters).valve_case.mesh;
    const int n = static_cast<int>(mesh.V.rows());
    x.resize(3 * n);
    w.assign(n, 1000.0);
    for (int i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) x[3 * i + d] = mesh.V(i, d) * (1.0 + 1e-3 * ((i + d) % 7));
    const Eigen::MatrixXi E = uniqueEdges(mesh.F), Q = bendingQuads(mesh.F);
    for (int e = 0; e < E.rows(); ++e)
      edges.push_back({E(e, 0), E(e, 1), (mesh.V.row(E(e, 0)) - mesh.V.row(E(e, 1))).norm(), 0.3});
    for (int f = 0; f < mesh.F.rows(); ++f)
      areas.push_back({mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2), 0.5, 1.0});
    for (int b = 0; b < Q.rows(); ++b)
      bends.push_back({Q(b, 0), Q(b, 1), Q(b, 2), Q(b, 3), 0.0, 3.0});
    orderByColour(edges, [](const DistanceConstraint& c) { return std::array<int, 2>{c.i, c.j}; });
    orderByColour(areas, [](const AreaConstraint& c) { return std::array<int, 3>{c.a, c.b, c.c}; });
    orderByColour(bends, [](const BendingConstraint& c) {
      return std::array<int, 4>{c.i, c.j, c.k, c.l};
    });
    // Contacts: every vertex against a triangle 10 faces away (geometry is irrelevant for cost).
    for (int f = 0; f < mesh.F.rows(); ++f) {
      ContactConstraint k;
      k.p = mesh.F((f + 10) % mesh.F.rows(), 0);
      k.a = mesh.F(f, 0), k.b = mesh.F(f, 1), k.c = mesh.F(f, 2);
      k.thickness = 1.0;
      if (k.p != k.a && k.p != k.b && k.p != k.c) contacts.push_back(k);
    }
  }
};

const KernelFixture& kernels() {
  static const KernelFixture fixture;
  return fixture;
}

template <class Sweep>
void runSweep(benchmark::State& state, size_t count, Sweep sweep) {
  std::vector<double> x = kernels().x, lambda(count, 0.0);
  for (auto _ : state) {
    sweep(x.data(), lambda.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * count));
  state.counters["ns_per_proj"] =
      benchmark::Counter(static_cast<double>(count), benchmark::Counter::kIsIterationInvariantRate |
                                                         benchmark::Counter::kInvert);
}

constexpr double kInvDt2 = 1e4;

void BM_ProjectionDistance(benchmark::State& state) {
  const auto& k = kernels();
  runSweep(state, k.edges.size(),
           [&](double* x, double* l) { projectDistances(k.edges, kInvDt2, x, k.w.data(), l); });
}
void BM_ProjectionArea(benchmark::State& state) {
  const auto& k = kernels();
  runSweep(state, k.areas.size(),
           [&](double* x, double* l) { projectAreas(k.areas, kInvDt2, x, k.w.data(), l); });
}
void BM_ProjectionBending(benchmark::State& state) {
  const auto& k = kernels();
  runSweep(state, k.bends.size(),
           [&](double* x, double* l) { projectBending(k.bends, kInvDt2, x, k.w.data(), l); });
}
void BM_ProjectionContact(benchmark::State& state) {
  const auto& k = kernels();
  runSweep(state, k.contacts.size(),
           [&](double* x, double* l) { projectContacts(k.contacts, x, k.w.data(), l); });
}
BENCHMARK(BM_ProjectionDistance);
BENCHMARK(BM_ProjectionArea);
BENCHMARK(BM_ProjectionBending);
BENCHMARK(BM_ProjectionContact);

}  // namespace
}  // namespace chordfit

BENCHMARK_MAIN();
