// Helpers shared by the tests: temporary directories, a tiny hand-built valve case, and
// running the chordfit executable with its output captured.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/case_data.h"
#include "core/simulator.h"

namespace chordfit::testing {

// A fresh directory under the system temp dir, removed on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// A truncated-cone "valve" small enough to check by hand:
//   annulus ring: 8 vertices on the circle r = 10 in z = 0 at angles k * 45 deg (k = 0..7);
//   free edge:    8 vertices on r = 6 at z = -8, same angles (indices 8..15);
//   anterior leaflet (label 0) = columns k = 7, 0, 1 (the +x side), posterior the rest.
// The annulus plane is z = 0 with n_AP = +z (leaflets hang below), a = +x, l = +y.
// Closed annulus = the open ring; no tracings, tips or cords.
ValveCase tinyConeCase();

// A bundled synthetic case (build/cases/<name>, cases/CMakeLists.txt) with its simulator
// settings; throws when it is missing or has no cords.
struct BundledCase {
  ValveCase valve_case;
  SimulationSettings settings;
};
BundledCase bundledCase(const std::string& name);

// Tracings of the closed state `closed_V` of `valve_case` on `planes` long-axis planes, without
// noise or dropout (sampler seed 1): the tracings a perfect reader would draw, so a fit can
// reproduce them exactly.
std::vector<Tracing> noiseFreeTracings(const ValveCase& valve_case, const Eigen::MatrixXd& closed_V,
                                       int planes);

// A bundled case closed with its own (seed) cords and traced there by a perfect reader
// (noiseFreeTracings on `planes` planes): `traced.tracings` replaced, `closed_V` that closure.
// Throws when the closure fails.
struct TracedSeedClosure {
  ValveCase traced;
  SimulationSettings settings;
  Eigen::MatrixXd closed_V;
};
TracedSeedClosure tracedSeedClosure(const std::string& name, int planes);

// Writes `text` to `path` (creating directories).
void writeText(const std::filesystem::path& path, const std::string& text);
std::string readText(const std::filesystem::path& path);

struct CommandResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

// A case.json "simulation" block that passes validation yet diverges: ten times the
// automatic time step (stiffness ratio 1000) without mass scaling, one iteration, the stiffest
// tissue and the highest pressure make the contacts blow up after ~1,000-4,000 steps (about
// 2 s on make-valve --edge 3). Used to check that a diverging run exits 3 and writes nothing.
inline constexpr const char* kDivergingSimulationJson =
    R"({"max_stiffness_ratio": 0, "stiffness_ratio": 1000, "max_step_mm": 100,
        "iterations": 1, "pressure_mmhg": 500, "youngs_modulus_mpa": 1000})";

// A path in single quotes for a shell command line (test paths hold no single quote).
inline std::string quoted(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

// How often `what` occurs in `text` (overlapping occurrences counted).
inline std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t count = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
    ++count;
  return count;
}

// Runs `program` with `arguments` (already shell-quoted where needed), stdin empty.
CommandResult runProgram(const std::filesystem::path& program, const std::string& arguments);

// Runs build/tools/chordfit with `arguments` (already shell-quoted where needed).
CommandResult runChordfit(const std::string& arguments);

}  // namespace chordfit::testing
