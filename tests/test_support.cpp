#include "tests/test_support.h"

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <sys/wait.h>
#include <unistd.h>

#include "core/case_io.h"
#include "core/closure_model.h"
#include "core/metrics.h"
#include "core/tracing_sampler.h"

namespace chordfit::testing {

namespace fs = std::filesystem;

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = fs::temp_directory_path() /
          ("chordfit-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  fs::remove_all(path_);
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

BundledCase bundledCase(const std::string& name) {
  Diagnostics diagnostics;
  auto loaded = loadCase(fs::path(CHORDFIT_CASES_DIR) / name, diagnostics);
  if (!loaded || !loaded->cords) throw std::runtime_error("bundled case " + name + " missing");
  BundledCase bundled;
  bundled.valve_case = *loaded;
  bundled.settings = settingsFromJson(bundled.valve_case.simulation_json, diagnostics);
  return bundled;
}

std::vector<Tracing> noiseFreeTracings(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                                       int planes) {
  TracingSamplerOptions sampler;
  sampler.planes = planes;
  sampler.noise_mm = 0.0;
  sampler.dropout_fraction = 0.0;
  SeededRandom random(1);
  return sampleTracings(closed_V, valve_case.mesh.F, valve_case.mesh.leaflet,
                        closedAnnulus(valve_case).frame, sampler, random);
}

ValveCase tinyConeCase() {
  ValveCase c;
  c.name = "tiny-cone";
  constexpr int kColumns = 8;
  c.mesh.V.resize(2 * kColumns, 3);
  for (int k = 0; k < kColumns; ++k) {
    const double phi = k * M_PI / 4.0;
    c.mesh.V.row(k) << 10.0 * std::cos(phi), 10.0 * std::sin(phi), 0.0;
    c.mesh.V.row(kColumns + k) << 6.0 * std::cos(phi), 6.0 * std::sin(phi), -8.0;
  }
  c.mesh.F.resize(2 * kColumns, 3);
  for (int k = 0; k < kColumns; ++k) {
    const int next = (k + 1) % kColumns;
    c.mesh.F.row(2 * k) << k, next, kColumns + k;
    c.mesh.F.row(2 * k + 1) << next, kColumns + next, kColumns + k;
  }
  c.mesh.leaflet.resize(2 * kColumns);
  for (int k = 0; k < kColumns; ++k) {
    const int label = (k == 7 || k == 0 || k == 1) ? 0 : 1;
    c.mesh.leaflet(k) = label;
    c.mesh.leaflet(kColumns + k) = label;
  }
  c.mesh.annulus.resize(kColumns);
  for (int k = 0; k < kColumns; ++k) c.mesh.annulus(k) = k;
  c.annulus_closed = c.mesh.V.topRows(kColumns);
  return c;
}

TracedSeedClosure tracedSeedClosure(const std::string& name, int planes) {
  const BundledCase bundled = bundledCase(name);
  const SimulationResult closed =
      simulateClosure(bundled.valve_case, *bundled.valve_case.cords, bundled.settings);
  if (!closed.ok()) throw std::runtime_error("bundled case " + name + ": " + closed.error);
  TracedSeedClosure t{bundled.valve_case, bundled.settings, closed.V};
  t.traced.tracings = noiseFreeTracings(bundled.valve_case, closed.V, planes);
  return t;
}

void writeText(const fs::path& path, const std::string& text) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CommandResult runProgram(const fs::path& program, const std::string& arguments) {
  TempDir capture;
  const fs::path out = capture / "stdout.txt";
  const fs::path err = capture / "stderr.txt";
  const std::string command =
      quoted(program) + " " + arguments + " >" + quoted(out) + " 2>" + quoted(err) + " </dev/null";
  const int status = std::system(command.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = readText(out);
  result.err = readText(err);
  return result;
}

CommandResult runChordfit(const std::string& arguments) {
  return runProgram(CHORDFIT_EXE, arguments);
}

}  // namespace chordfit::testing
