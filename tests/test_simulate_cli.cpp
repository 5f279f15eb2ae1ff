// `chordfit simulate` and `chordfit sweep-cord` end to end on a coarse parametric valve and the
// bundled small case.
#include <algorithm>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/test_support.h"

namespace chordfit {
namespace {

using testing::runChordfit;
using testing::TempDir;

using testing::quoted;

class SimulateCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(runChordfit("make-valve --out " + quoted(case_dir_) + " --edge 3.0").exit_code, 0);
  }
  TempDir dir_;
  std::filesystem::path case_dir_ = dir_ / "case";
};

TEST_F(SimulateCommand, WritesTheClosedMeshWithScalarsAndMetrics) {
  const auto r =
      runChordfit("simulate " + quoted(case_dir_) + " --quiet --out " + quoted(dir_ / "sim"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| Case | Area"), std::string::npos) << r.out;
  const auto metrics = nlohmann::json::parse(testing::readText(dir_ / "sim" / "metrics.json"));
  for (const char* key :
       {"min_mm", "median_mm", "max_mm", "mean_mm", "sd_mm", "area_mm2", "prolapse_segments",
        "prolapse_max_height_mm", "converged", "steps", "dt_ms", "sim_seconds"}) {
    EXPECT_TRUE(metrics.contains(key)) << key;
  }
  EXPECT_GT(metrics["steps"].get<int>(), 0);
  EXPECT_GT(metrics["dt_ms"].get<double>(), 0.0);
  // A 3 mm mesh is coarse against the 1 mm thickness: edge midpoints join the contact points.
  EXPECT_TRUE(metrics["edge_contact"].get<bool>());
  EXPECT_NE(r.out.find("(edge midpoints as contact points too)"), std::string::npos) << r.out;
  EXPECT_EQ(metrics["self_intersections"].get<int>(), 0) << "the leaflets do not cross";
  EXPECT_NE(r.out.find("leaflets passing through:        none"), std::string::npos) << r.out;
  const std::string vtk = testing::readText(dir_ / "sim" / "closed.vtk");
  EXPECT_NE(vtk.find("SCALARS height_above_annulus_plane_mm"), std::string::npos);
  EXPECT_NE(vtk.find("SCALARS distance_to_tracing_mm"), std::string::npos);
  EXPECT_NE(
      testing::readText(dir_ / "sim" / "closed.ply").find("property float prolapse_height_mm"),
      std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim" / "sections.svg"))
      << "no tracings, no figure of them";
  // The files were staged and moved in; nothing of the staging is left.
  for (const auto& entry : std::filesystem::directory_iterator(dir_ / "sim"))
    EXPECT_NE(entry.path().filename().string().rfind(".staging-", 0), 0u) << entry.path();
}

TEST_F(SimulateCommand, RemovesTheOpenedStateAnEarlierOpeningRunLeftAndKeepsOtherFiles) {
  // An earlier `simulate --phase open` into the same directory; its opened state beside this
  // run's closure would read as this run's. A file the user put there stays.
  const std::filesystem::path out = dir_ / "sim";
  const auto opening =
      runChordfit("simulate " + quoted(case_dir_) + " --phase open --quiet --out " + quoted(out));
  ASSERT_EQ(opening.exit_code, 0) << opening.err;
  ASSERT_TRUE(std::filesystem::exists(out / "opened.ply"));
  // The opening is measured against the closure's distance from the open state: it goes back.
  const auto opened = nlohmann::json::parse(testing::readText(out / "metrics.json"))["open_phase"];
  EXPECT_LT(opened["mean_distance_to_open_state_mm"].get<double>(),
            opened["closed_mean_distance_to_open_state_mm"].get<double>());
  testing::writeText(out / "notes.txt", "the user's");
  const auto r = runChordfit("simulate " + quoted(case_dir_) + " --quiet --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out / "opened.ply"));
  EXPECT_FALSE(std::filesystem::exists(out / "opened.vtk"));
  EXPECT_EQ(testing::readText(out / "notes.txt"), "the user's");
  EXPECT_TRUE(std::filesystem::exists(out / "closed.ply"));
  EXPECT_NE(r.out.find("wrote " + (out / "closed.ply").string() +
                       ", closed.vtk, metrics.json, enface.svg; removed opened.ply, opened.vtk "
                       "(an earlier run's)\n"),
            std::string::npos)
      << r.out;
}

TEST_F(SimulateCommand, KeepsAFileOfAnOutputsNameThatNoRunWrote) {
  // opened.ply put there by hand (no chordfit run recorded it) is the user's, not stale.
  const std::filesystem::path out = dir_ / "sim";
  std::filesystem::create_directories(out);
  testing::writeText(out / "opened.ply", "the user's");
  const auto r = runChordfit("simulate " + quoted(case_dir_) + " --quiet --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(testing::readText(out / "opened.ply"), "the user's");
  EXPECT_EQ(r.out.find("removed"), std::string::npos) << r.out;
}

TEST_F(SimulateCommand, SetOverridesASettingAsTheCasesSimulationBlockWould) {
  // --set gives the closure and the metrics of a case whose case.json says so (the contact
  // thickness also enters the metrics' orifice coverage), and another closure than the
  // defaults; the overrides are recorded in metrics.json.
  const std::string set = " --set youngs_modulus_mpa=4 --set contact_thickness_mm=1.2";
  const auto r =
      runChordfit("simulate " + quoted(case_dir_) + set + " --quiet --out " + quoted(dir_ / "set"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::filesystem::path edited = dir_ / "edited";
  std::filesystem::copy(case_dir_, edited, std::filesystem::copy_options::recursive);
  auto case_json = nlohmann::json::parse(testing::readText(edited / "case.json"));
  case_json["simulation"]["youngs_modulus_mpa"] = 4;
  case_json["simulation"]["contact_thickness_mm"] = 1.2;
  testing::writeText(edited / "case.json", case_json.dump(2));
  ASSERT_EQ(runChordfit("simulate " + quoted(edited) + " --quiet --out " + quoted(dir_ / "json"))
                .exit_code,
            0);
  ASSERT_EQ(runChordfit("simulate " + quoted(case_dir_) + " --quiet --out " + quoted(dir_ / "3"))
                .exit_code,
            0);
  const std::string closed = testing::readText(dir_ / "set" / "closed.ply");
  EXPECT_EQ(closed, testing::readText(dir_ / "json" / "closed.ply"));
  EXPECT_NE(closed, testing::readText(dir_ / "3" / "closed.ply"));
  auto metrics = nlohmann::json::parse(testing::readText(dir_ / "set" / "metrics.json"));
  auto edited_metrics = nlohmann::json::parse(testing::readText(dir_ / "json" / "metrics.json"));
  EXPECT_EQ(metrics["settings_overrides"],
            nlohmann::json({"youngs_modulus_mpa=4", "contact_thickness_mm=1.2"}));
  for (nlohmann::json* m : {&metrics, &edited_metrics}) {
    m->erase("settings_overrides");
    m->erase("sim_seconds");
  }
  EXPECT_EQ(metrics, edited_metrics);
}

// A load faster than the calibrated 10 mmHg/ms gets a note with its rate: a 1e-300 ms ramp
// printed that rate with 300 digits, and ramp_ms 0 (the whole load at once) went without one.
TEST_F(SimulateCommand, NotesALoadFasterThanCalibratedWithItsRate) {
  const auto noteOf = [&](const std::string& ramp) {
    const auto r = runChordfit("simulate " + quoted(case_dir_) + " --set ramp_ms=" + ramp +
                               " --quiet --out " + quoted(dir_ / ("ramp" + ramp)));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const std::size_t at = r.err.find("note: simulate: 100 mmHg ");
    return at == std::string::npos ? std::string() : r.err.substr(at, r.err.find('\n', at) - at);
  };
  EXPECT_NE(noteOf("1e-300").find("over a 1e-300 ms ramp loads the valve at 1e+302 mmHg/ms, "
                                  "faster than calibrated"),
            std::string::npos);
  EXPECT_NE(noteOf("0").find("at once (ramp_ms 0) loads the valve, faster than calibrated"),
            std::string::npos);
  EXPECT_EQ(noteOf("10"), "");
}

TEST_F(SimulateCommand, RejectsABadSetBeforeSimulatingNamingTheSetting) {
  const std::pair<const char*, const char*> cases[] = {
      {"--set youngs_modulus_mpa=-1", "simulate: --set: simulation.youngs_modulus_mpa: -1 is out"},
      {"--set unknown_thing=1", "simulate: --set: simulation.unknown_thing: unknown"},
      {"--set contact=1", "simulate: --set: simulation.contact: expected true or false"},
      {"--set youngs_modulus_mpa=3,5", "youngs_modulus_mpa=3,5: \"3,5\" is not a number"},
      {"--set youngs_modulus_mpa", "simulate: --set: expected KEY=VALUE"},
      {"--set pressure_mmhg=90 --set pressure_mmhg=80", "pressure_mmhg given twice"},
      {"--set phase=open", "phase cannot be set (--phase chooses it)"},
      // The case's ramp fits under its cap; the override's cap does not: the override is named.
      {"--set max_steps=10", "simulate: --set: simulation.max_steps: "}};
  for (const auto& [option, message] : cases) {
    const auto r = runChordfit("simulate " + quoted(case_dir_) + " " + option + " --out " +
                               quoted(dir_ / "bad"));
    EXPECT_EQ(r.exit_code, 2) << option;
    EXPECT_NE(r.err.find(message), std::string::npos) << option << ": " << r.err;
    EXPECT_EQ(r.out.find("closure"), std::string::npos) << option << ": simulated first";
    EXPECT_FALSE(std::filesystem::exists(dir_ / "bad" / "closed.ply")) << option;
  }
}

TEST(SimulateCommandWithTracings, DrawsTheClosedValveAgainstTheTracingsOfEveryPlane) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  const auto r = runChordfit("simulate " + quoted(small) + " --quiet --out " + quoted(dir / "sim"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("sections.svg"), std::string::npos) << r.out;
  const std::string svg = testing::readText(dir / "sim" / "sections.svg");
  for (const char* text : {">simulated closed, anterior<", ">simulated closed, posterior<",
                           ">tracing points<", ">closed annulus<", ">plane 0: ", ">plane 2: "}) {
    EXPECT_NE(svg.find(text), std::string::npos) << text;
  }
  EXPECT_EQ(svg.find(">plane 3: "), std::string::npos) << "the case has 3 tracing planes";
}

// Issue 3: two runs, one with 1 thread and one with 2, write identical bytes (on this coarse
// valve the threads share the contact detection; SimulatorDeterminism.TwoSimulatorThreads…
// splits the constraint sweeps of a finer one too).
TEST_F(SimulateCommand, IsDeterministicByteForByteWithOneOrTwoThreads) {
  const std::string args = "simulate " + quoted(case_dir_) + " --quiet";
  ASSERT_EQ(runChordfit(args + " --threads 1 --out " + quoted(dir_ / "a")).exit_code, 0);
  ASSERT_EQ(runChordfit(args + " --threads 2 --out " + quoted(dir_ / "b")).exit_code, 0);
  EXPECT_EQ(testing::readText(dir_ / "a" / "closed.ply"),
            testing::readText(dir_ / "b" / "closed.ply"));
  EXPECT_EQ(testing::readText(dir_ / "a" / "closed.vtk"),
            testing::readText(dir_ / "b" / "closed.vtk"));
  const auto metrics = nlohmann::json::parse(testing::readText(dir_ / "b" / "metrics.json"));
  EXPECT_EQ(metrics["threads"].get<int>(), 2);
  EXPECT_FALSE(metrics["threads_gave_up"].get<bool>()) << "two threads that fell back to one";
}

TEST_F(SimulateCommand, RejectsAThreadCountOutOfRange) {
  const auto r =
      runChordfit("simulate " + quoted(case_dir_) + " --threads 0 --out " + quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--threads"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim"));
}

// An output place that cannot be written is found before the closure, exit 2.
TEST_F(SimulateCommand, RejectsAnOutputDirectoryInsideAFileBeforeSimulating) {
  testing::writeText(dir_ / "a-file", "x");
  const auto r = runChordfit("simulate " + quoted(case_dir_) + " --quiet --out " +
                             quoted(dir_ / "a-file" / "sim"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("/a-file is not a directory"), std::string::npos) << r.err;
}

// --out naming a file: said once ("--out: X: X is not a directory" named it twice).
TEST_F(SimulateCommand, RejectsAnOutputDirectoryThatIsAFileNamingItOnce) {
  testing::writeText(dir_ / "a-file", "x");
  const std::string out = (dir_ / "a-file").string();
  const auto r =
      runChordfit("simulate " + quoted(case_dir_) + " --quiet --out " + quoted(dir_ / "a-file"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--out: " + out + ": exists and is not a directory"), std::string::npos)
      << r.err;
}

TEST_F(SimulateCommand, ADirectoryInTheWayOfAnOutputFileIsFoundBeforeSimulating) {
  // A directory named like an output file would make the final rename fail after the closure
  // (StagedOutput::publish still refuses it then, leaving the old outputs); it is a usage error
  // found before any work.
  const auto out = dir_ / "sim";
  std::filesystem::create_directories(out / "enface.svg" / "keep");
  testing::writeText(out / "closed.ply", "old");
  const auto r = runChordfit("simulate " + quoted(case_dir_) + " --out " + quoted(out));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: simulate: --out: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("enface.svg: a directory of that name is in the way"), std::string::npos)
      << r.err;
  EXPECT_EQ(r.out.find("closure"), std::string::npos) << "simulated first: " << r.out;
  EXPECT_EQ(testing::readText(out / "closed.ply"), "old");
  EXPECT_FALSE(std::filesystem::exists(out / "metrics.json"));
  for (const auto& entry : std::filesystem::directory_iterator(out))
    EXPECT_NE(entry.path().filename().string().rfind(".staging", 0), 0u) << "staging left";
}

TEST_F(SimulateCommand, AStepCapThatEndsDuringThePressureRampIsAnInputError) {
  // With the automatic time step the ramp's length in steps depends on the mesh; such a run
  // stopped mid-ramp and reported "not converged" with exit 0. validate says so too.
  nlohmann::json c = nlohmann::json::parse(testing::readText(case_dir_ / "case.json"));
  c["simulation"] = {{"max_steps", 10}};
  testing::writeText(case_dir_ / "case.json", c.dump());
  const auto r =
      runChordfit("simulate " + quoted(case_dir_) + " --quiet --out " + quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("simulation.max_steps: 10 ends before the 10 ms pressure ramp does"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim" / "metrics.json"));
  const auto validated = runChordfit("validate " + quoted(case_dir_));
  EXPECT_EQ(validated.exit_code, 2) << validated.out;
  EXPECT_NE(validated.err.find("simulation.max_steps: 10 ends before"), std::string::npos)
      << validated.err;
  // metrics runs no closure: the step cap is no reason to refuse it.
  const auto measured =
      runChordfit("metrics " + quoted(case_dir_) + " --mesh " + quoted(case_dir_ / "open.ply"));
  EXPECT_EQ(measured.exit_code, 0) << measured.err;
}

// Stiff tissue factors shorten the automatic time step; such a run was refused as
// "case.json: simulation.max_steps", whether or not case.json had a simulation block.
TEST_F(SimulateCommand, AStepCapTheTissuesFactorsOutrunNamesTheTissue) {
  nlohmann::json c = nlohmann::json::parse(testing::readText(case_dir_ / "case.json"));
  c["simulation"] = {{"max_steps", 1000}};  // enough for the uniform tissue's ramp
  testing::writeText(case_dir_ / "case.json", c.dump());
  const std::string ply = testing::readText(case_dir_ / "open.ply");
  const std::string count_key = "element vertex ";
  const std::size_t count_at = ply.find(count_key) + count_key.size();
  const int vertices = std::stoi(ply.substr(count_at));
  const nlohmann::json tissue = {{"stiffness", std::vector<double>(vertices, 1000.0)}};
  testing::writeText(dir_ / "stiff.json", tissue.dump());

  const auto r =
      runChordfit("simulate " + quoted(case_dir_) + " --tissue " + quoted(dir_ / "stiff.json") +
                  " --quiet --out " + quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find((dir_ / "stiff.json").string() +
                       ": stiffness: factors up to 1000 shorten the automatic time step"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("more than simulation.max_steps = 1000; raise it (--set max_steps="),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("case.json"), r.err.find("case.json's simulation block")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim" / "metrics.json"));
  // compare reads its --tissues after the case's settings: named there too, before any
  // closure (it was blamed on the cord file once the closure ran).
  ASSERT_EQ(
      runChordfit("heuristic " + quoted(case_dir_) + " --out " + quoted(dir_ / "h.json")).exit_code,
      0);
  const auto compared =
      runChordfit("compare " + quoted(case_dir_) + " " + quoted(dir_ / "h.json") + " --tissues " +
                  quoted(dir_ / "stiff.json") + " --out " + quoted(dir_ / "cmp"));
  EXPECT_EQ(compared.exit_code, 2) << compared.out << compared.err;
  EXPECT_NE(compared.err.find("error: compare: --tissues: " + (dir_ / "stiff.json").string() +
                              ": stiffness: factors up to 1000 shorten the automatic time step"),
            std::string::npos)
      << compared.err;
  EXPECT_EQ((compared.out + compared.err).find("closing"), std::string::npos) << compared.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "cmp"));

  // The case's own tissue: named at case.json's tissue_stiffness; validate has no --set.
  c["tissue_stiffness"] = "tissue.json";
  testing::writeText(case_dir_ / "case.json", c.dump());
  testing::writeText(case_dir_ / "tissue.json", tissue.dump());
  const auto validated = runChordfit("validate " + quoted(case_dir_));
  EXPECT_EQ(validated.exit_code, 2) << validated.out;
  EXPECT_NE(validated.err.find("error: case.json: tissue_stiffness: factors up to 1000"),
            std::string::npos)
      << validated.err;
  EXPECT_EQ(validated.err.find("--set"), std::string::npos) << validated.err;
  // A cap raised as the message says lets the closure run.
  const auto raised = runChordfit("simulate " + quoted(case_dir_) +
                                  " --set max_steps=6000 --quiet --out " + quoted(dir_ / "sim"));
  EXPECT_EQ(raised.exit_code, 0) << raised.err;
}

// A file output over one of the case's files (metrics --out onto the mesh it measured, a
// heuristic cord set over case.json) used to exit 0 and leave a case that no longer loads.
TEST_F(SimulateCommand, FileOutputsDoNotWriteOverTheCasesFiles) {
  const std::string mesh = testing::readText(case_dir_ / "open.ply");
  auto r = runChordfit("metrics " + quoted(case_dir_) + " --mesh " +
                       quoted(case_dir_ / "open.ply") + " --out " + quoted(case_dir_ / "open.ply"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("open.ply: is an input of this run; metrics would write over it"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(testing::readText(case_dir_ / "open.ply"), mesh);
  // A curve file a tracing names is the case's too (tracings.json -> "file").
  testing::writeText(case_dir_ / "tracings.json",
                     R"({"tracings": [{"plane": {"origin": [0, 0, 0], "normal": [0, 1, 0]},
                                       "file": "curve.json"}]})");
  testing::writeText(case_dir_ / "curve.json", R"({"points": [[1, 0, -2], [2, 0, -3]]})");
  nlohmann::json c = nlohmann::json::parse(testing::readText(case_dir_ / "case.json"));
  c["tracings"] = "tracings.json";
  testing::writeText(case_dir_ / "case.json", c.dump());
  r = runChordfit("metrics " + quoted(case_dir_) + " --mesh " + quoted(case_dir_ / "open.ply") +
                  " --out " + quoted(case_dir_ / "curve.json"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("curve.json: is an input of this run"), std::string::npos) << r.err;
  r = runChordfit("heuristic " + quoted(case_dir_) + " --out " + quoted(case_dir_ / "case.json"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("case.json: is an input of this run"), std::string::npos) << r.err;
  EXPECT_EQ(testing::readText(case_dir_ / "curve.json"), R"({"points": [[1, 0, -2], [2, 0, -3]]})");
}

TEST_F(SimulateCommand, RejectsAnUnknownPhase) {
  const auto r = runChordfit("simulate " + quoted(case_dir_) + " --phase sideways --out " +
                             quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: simulate: --phase: expected close or open"), std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim" / "closed.ply"));
}

// A cord file that is not an object: said once (it was said once per key looked up).
TEST_F(SimulateCommand, RejectsACordFileThatIsNotAnObjectInOneLine) {
  testing::writeText(dir_ / "array.json", "[1, 2, 3]");
  const auto r = runChordfit("simulate " + quoted(case_dir_) + " --cords " +
                             quoted(dir_ / "array.json") + " --out " + quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 2);
  const std::string line = "(top level): expected an object, got array";
  ASSERT_NE(r.err.find(line), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(line), r.err.rfind(line)) << r.err;
}

TEST_F(SimulateCommand, RejectsAMissingCordsFile) {
  const auto r = runChordfit("simulate " + quoted(case_dir_) + " --cords " +
                             quoted(dir_ / "none.json") + " --out " + quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("file not found"), std::string::npos) << r.err;
}

TEST_F(SimulateCommand, RejectsAnUnknownSimulationOverride) {
  nlohmann::json c = nlohmann::json::parse(testing::readText(case_dir_ / "case.json"));
  c["simulation"] = {{"presure_mmhg", 100}};
  testing::writeText(case_dir_ / "case.json", c.dump());
  const auto r = runChordfit("simulate " + quoted(case_dir_) + " --out " + quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("simulation.presure_mmhg"), std::string::npos) << r.err;
}

TEST_F(SimulateCommand, RejectsOutOfRangeSimulationSettingsNamingFileKeyAndProblem) {
  // 1e300 mmHg used to "converge" in 28 steps; now every setting is range-checked up front.
  nlohmann::json c = nlohmann::json::parse(testing::readText(case_dir_ / "case.json"));
  c["simulation"] = {
      {"pressure_mmhg", 1e300}, {"thickness_mm", -1.0}, {"tolerance_mm", 0.0}, {"iterations", 0}};
  testing::writeText(case_dir_ / "case.json", c.dump());
  const auto r =
      runChordfit("simulate " + quoted(case_dir_) + " --quiet --out " + quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 2);
  for (const char* key : {"simulation.pressure_mmhg", "simulation.thickness_mm",
                          "simulation.tolerance_mm", "simulation.iterations"}) {
    EXPECT_NE(r.err.find(key), std::string::npos) << key << "\n" << r.err;
  }
  EXPECT_NE(r.err.find("case.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("out of range"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim" / "closed.ply"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim" / "metrics.json"));
}

TEST_F(SimulateCommand, ADivergingRunExitsWith3AndWritesNoOutput) {
  // Settings inside their ranges can still break a run (testing::kDivergingSimulationJson);
  // the step loop must stop with an error instead of writing the positions.
  nlohmann::json c = nlohmann::json::parse(testing::readText(case_dir_ / "case.json"));
  c["simulation"] = nlohmann::json::parse(testing::kDivergingSimulationJson);
  testing::writeText(case_dir_ / "case.json", c.dump());
  const auto r =
      runChordfit("simulate " + quoted(case_dir_) + " --quiet --out " + quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("diverged"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim" / "closed.ply"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim" / "closed.vtk"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim" / "metrics.json"));
}

// A modulus within its range but far too soft for the pressure stretches the sheet without any
// vertex going far or fast: at 0.001 MPa the closure reported 5,900 times the open area, 457
// crossing pairs, as a result (exit 0). The area check calls it a divergence.
TEST_F(SimulateCommand, ASheetStretchedManyTimesItsAreaIsADivergenceNotAResult) {
  const auto r =
      runChordfit("simulate " + quoted(case_dir_) +
                  " --set youngs_modulus_mpa=0.001 --quiet --out " + quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("simulation diverged: the leaflets stretched to "), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("youngs_modulus_mpa 0.001"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim" / "metrics.json"));
  const auto soft =
      runChordfit("simulate " + quoted(case_dir_) + " --set youngs_modulus_mpa=0.5 --quiet --out " +
                  quoted(dir_ / "soft"));
  EXPECT_EQ(soft.exit_code, 0) << "soft tissue that holds together is a result: " << soft.err;
  // The result itself is checked, not only the run every 100 steps: on the bundled small case
  // 0.045 MPa passes 4 times its area early, and ends at 4.5 times.
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  const auto end =
      runChordfit("simulate " + quoted(small) + " --set youngs_modulus_mpa=0.045 --quiet --out " +
                  quoted(dir_ / "end"));
  EXPECT_EQ(end.exit_code, 3) << end.err;
  EXPECT_NE(end.err.find("times their rest area ("), std::string::npos) << end.err;
  EXPECT_NE(end.err.find(") at the end;"), std::string::npos) << end.err;
}

// sweep-cord over a short range: one row per scale, the same bytes with 1 or 2 threads.
TEST(SweepCordCommand, WritesOneRowPerScaleWhateverTheThreadCount) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  const std::string args = "sweep-cord " + quoted(small) + " --range 0.02 --step 0.005 --window 2";
  const auto one = runChordfit(args + " --threads 1 --out " + quoted(dir / "one"));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const auto two = runChordfit(args + " --threads 2 --out " + quoted(dir / "two"));
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_NE(one.err.find("over 9 scales, 1 thread\n"), std::string::npos) << one.err;
  EXPECT_NE(two.err.find("over 9 scales, 2 threads\n"), std::string::npos) << two.err;
  const std::string csv = testing::readText(dir / "one" / "sweep.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 9) << "header + scales 0.98..1.02";
  EXPECT_EQ(csv, testing::readText(dir / "two" / "sweep.csv"));
  // Each closure's crossing triangle pairs, none on this valve (the last column).
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "scale,mean_deviation_mm,vertex_x_mm,vertex_y_mm,vertex_z_mm,vertex_height_mm,"
            "converged,steps,self_intersections");
  for (std::size_t at = csv.find('\n'); at + 1 < csv.size(); at = csv.find('\n', at + 1))
    EXPECT_EQ(csv.substr(csv.rfind(',', csv.find('\n', at + 1)) + 1,
                         csv.find('\n', at + 1) - csv.rfind(',', csv.find('\n', at + 1)) - 1),
              "0");
  const auto summary = nlohmann::json::parse(testing::readText(dir / "one" / "sweep.json"));
  EXPECT_EQ(summary["closures_with_self_intersections"], 0);
  EXPECT_EQ(one.err.find("pass through each other"), std::string::npos) << one.err;
  EXPECT_GT(summary["vertex_height"]["change_over_0.5_percent"].get<double>(), 0.0);
  EXPECT_TRUE(std::filesystem::exists(dir / "one" / "sweep.svg"));
  // The verdict, in sweep.json and on the printed line: this taut cord moves the map.
  const auto& height = summary["vertex_height"];
  EXPECT_FALSE(height["flat"].get<bool>());
  EXPECT_EQ(height["smooth"].get<bool>(), height["signal_to_noise"].get<double>() >= 10.0);
  EXPECT_NE(one.out.find(height["smooth"].get<bool>() ? "| smooth" : "| NOT smooth"),
            std::string::npos)
      << one.out;
}

// A step that does not divide the range: the scales 1 + k step stay within [1 - range,
// 1 + range] and include 1, the cord as given (they ran 0.99, 0.994, ..., 1.010 here).
TEST(SweepCordCommand, AStepThatDoesNotDivideTheRangeGivesScalesCentredOnOne) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  const auto r = runChordfit("sweep-cord " + quoted(small) +
                             " --range 0.01 --step 0.004 --window 2 --out " + quoted(dir / "s"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("the scales run from 0.992 to 1.008, centred on 1"), std::string::npos)
      << r.err;
  std::istringstream csv(testing::readText(dir / "s" / "sweep.csv"));
  std::string line;
  std::getline(csv, line);  // header
  std::vector<double> scales;
  while (std::getline(csv, line)) scales.push_back(std::stod(line.substr(0, line.find(','))));
  const std::vector<double> expected = {0.992, 0.996, 1.0, 1.004, 1.008};
  ASSERT_EQ(scales.size(), expected.size());
  for (std::size_t k = 0; k < scales.size(); ++k) EXPECT_NEAR(scales[k], expected[k], 1e-12);
  EXPECT_EQ(scales[2], 1.0) << "the cord as given, exactly";
}

// Without --cord the sweep takes the P2 primary nearest the posterior midline; a set without
// one asks for --cord (it blamed "--cord: no such cord", an option the user never gave).
TEST(SweepCordCommand, ASetWithoutAP2PrimaryAsksForTheCord) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  auto cords = nlohmann::json::parse(testing::readText(small / "cords.json"));
  for (auto& cord : cords["cords"]) cord["kind"] = "secondary";
  testing::writeText(dir / "secondaries.json", cords.dump());
  const auto r = runChordfit("sweep-cord " + quoted(small) + " --cords " +
                             quoted(dir / "secondaries.json") + " --out " + quoted(dir / "s"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: sweep-cord: the cord set has no P2 primary cord to sweep by "
                       "default (32 cords): give --cord K"),
            std::string::npos)
      << r.err;
}

// A set without cords has nothing to sweep; it was asked for a --cord it could not have.
TEST(SweepCordCommand, ASetWithoutCordsIsRefusedAsSuch) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  auto cords = nlohmann::json::parse(testing::readText(small / "cords.json"));
  cords["cords"] = nlohmann::json::array();
  testing::writeText(dir / "none.json", cords.dump());
  const auto r = runChordfit("sweep-cord " + quoted(small) + " --cords " +
                             quoted(dir / "none.json") + " --out " + quoted(dir / "s"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("none.json has no cords: nothing to sweep"), std::string::npos) << r.err;
}

// A cord slack over the whole range moves nothing: "flat", not a signal/noise read as noisy.
TEST(SweepCordCommand, CallsTheMapOfACordSlackThroughoutFlat) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  auto cords = nlohmann::json::parse(testing::readText(small / "cords.json"));
  cords["cords"][0]["rest_length_mm"] = 2.0 * cords["cords"][0]["rest_length_mm"].get<double>();
  testing::writeText(dir / "slack.json", cords.dump());
  const auto r =
      runChordfit("sweep-cord " + quoted(small) + " --cords " + quoted(dir / "slack.json") +
                  " --cord 0 --range 0.01 --step 0.004 --window 2 --out " + quoted(dir / "sweep"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary = nlohmann::json::parse(testing::readText(dir / "sweep" / "sweep.json"));
  EXPECT_TRUE(summary["vertex_height"]["flat"].get<bool>());
  EXPECT_FALSE(summary["vertex_height"]["smooth"].get<bool>());
  EXPECT_NE(r.out.find("flat: it does not move over the range"), std::string::npos) << r.out;
  // No noise either: the ratio is not a number to print (it printed "inf").
  EXPECT_NE(r.out.find("signal/noise - (no noise) | flat"), std::string::npos) << r.out;
}

// --set changes the closures of the sweep (another CSV than the case's settings give) and is
// recorded in sweep.json.
TEST(SweepCordCommand, SetChangesEveryClosureAndIsRecorded) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  const std::string args = "sweep-cord " + quoted(small) + " --range 0.01 --step 0.004 --window 2";
  ASSERT_EQ(runChordfit(args + " --out " + quoted(dir / "plain")).exit_code, 0);
  const auto r = runChordfit(args + " --set pressure_mmhg=80 --out " + quoted(dir / "set"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(testing::readText(dir / "set" / "sweep.csv"),
            testing::readText(dir / "plain" / "sweep.csv"));
  const auto summary = nlohmann::json::parse(testing::readText(dir / "set" / "sweep.json"));
  EXPECT_EQ(summary["settings_overrides"], nlohmann::json({"pressure_mmhg=80"}));
}

// A sweep fails at its lowest failing scale, the same for any thread count, and stops there:
// every closure of a diverging sweep used to run before it failed.
TEST(SweepCordCommand, StopsAtItsLowestFailingScaleWhateverTheThreadCount) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  for (const int threads : {1, 2}) {
    const auto r =
        runChordfit("sweep-cord " + quoted(small) + " --set youngs_modulus_mpa=0.001 --threads " +
                    std::to_string(threads) + " --out " + quoted(dir / "sweep"));
    EXPECT_EQ(r.exit_code, 3) << r.err;
    EXPECT_NE(r.err.find("[  1/101] scale 0.9500: failed (below)"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("[  2/101]"), std::string::npos) << "printed past the failure: " << r.err;
    EXPECT_NE(r.err.find("simulation failed at scale 0.95: simulation diverged"), std::string::npos)
        << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "sweep"));
  }
}

TEST(SweepCordCommand, RejectsBadOptionsWithExitCode2NamingTheOption) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  const std::pair<std::string, std::string> cases[] = {
      {"--cord -2", "--cord"},
      {"--cord -1", "--cord: must be a cord index >= 0, got -1"},
      {"--cord 9999", "--cord: no such cord"},
      {"--threads 0", "--threads"},
      {"--window 1", "--window"},
      {"--range 0.02 --step 0.005", "--window 5 needs at least 11 scales"},
      {"--step 0", "--range/--step"},
      {"--set iterations=0", "sweep-cord: --set: simulation.iterations"}};
  for (const auto& [options, message] : cases) {
    const auto r = runChordfit("sweep-cord " + quoted(small) + " " + options + " --out " +
                               quoted(dir / "sweep"));
    EXPECT_EQ(r.exit_code, 2) << options;
    EXPECT_NE(r.err.find(message), std::string::npos) << options << ": " << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "sweep" / "sweep.csv"));
}

// --window 1073741824 used to pass (2 * window + 1 overflowed to a negative count) and crash
// after all the closures; the window is checked against the largest sweep up front.
TEST(SweepCordCommand, RefusesAWindowNoSweepCanFillBeforeAnyClosure) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  for (const char* window : {"1001", "1073741824"}) {
    const auto r = runChordfit("sweep-cord " + quoted(small) + " --window " + window +
                               " --range 0.002 --step 0.001 --out " + quoted(dir / "sweep"));
    EXPECT_EQ(r.exit_code, 2) << window << ": " << r.err;
    EXPECT_NE(r.err.find("error: sweep-cord: --window: must be >= 2 and <= 1000, got " +
                         std::string(window)),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find("sweeping cord"), std::string::npos) << "no closure may start";
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "sweep"));
}

// --step 1e-9 used to die in std::bad_alloc (exit 1) and --step 1e-6 to start 100,001
// closures: the scale count is computed in double and capped before the case is read.
TEST(SweepCordCommand, RefusesMoreThan2001ScalesNamingTheCountBeforeAnyClosure) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  const std::pair<std::string, std::string> cases[] = {
      {"--step 1e-6", "--range/--step: 0.05/1e-06 give 100001 scales"},
      {"--step 1e-9", "--range/--step: 0.05/1e-09 give 1e+08 scales"},
      {"--range 0.1 --step 0.0000999", "--range/--step: 0.1/9.99e-05 give 2003 scales"}};
  for (const auto& [options, message] : cases) {
    const auto r = runChordfit("sweep-cord " + quoted(small) + " " + options + " --out " +
                               quoted(dir / "sweep"));
    EXPECT_EQ(r.exit_code, 2) << options << ": " << r.err;
    EXPECT_NE(r.err.find("error: sweep-cord: " + message), std::string::npos)
        << options << ": " << r.err;
    EXPECT_NE(r.err.find("at most 2001"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("sweeping cord"), std::string::npos) << "no closure may start";
  }
}

// --cords <a directory> used to be "parsed" and reported as malformed JSON.
TEST(SimulateCords, ACordsOptionNamingADirectoryIsRefusedAsADirectory) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  std::filesystem::create_directory(dir / "cords.json");
  const auto r = runChordfit("simulate " + quoted(small) + " --cords " +
                             quoted(dir / "cords.json") + " --out " + quoted(dir / "sim"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(
      r.err.find("error: " + (dir / "cords.json").string() + ": is a directory, not a JSON file"),
      std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "sim"));
}

}  // namespace
}  // namespace chordfit
