// The chordfit program end to end: the foundation pipeline (make-valve -> validate ->
// heuristic -> metrics), the documented example case, and usage errors.
#include <algorithm>
#include <cmath>
#include <optional>
#include <regex>
#include <utility>

#include <sys/stat.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/case_io.h"
#include "core/cordset_io.h"
#include "core/curve_io.h"
#include "core/mesh_io.h"
#include "core/metrics.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

using testing::runChordfit;
using testing::TempDir;

using testing::quoted;

// A mistyped option is an unexpected argument to CLI11; the message names the option meant.
TEST(Cli, AMistypedOptionSuggestsTheOptionMeant) {
  const auto r = testing::runChordfit("simulate " + testing::quoted(testing::TempDir().path()) +
                                      " --thread 2 --out x");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("  --thread: did you mean \"--threads\"?"), std::string::npos) << r.err;
}

// --version names the revision the binary was built from (cmake/write_revision.cmake): the
// benchmark records it with every job.
TEST(Cli, VersionNamesTheSourceRevision) {
  const auto r = testing::runChordfit("--version");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::regex_search(r.out, std::regex("^chordfit 0\\.1\\.0 \\(revision [^ )]+\\)\n")))
      << r.out;
}

TEST(ChordfitCli, RunsTheFoundationPipelineOnAParametricValve) {
  TempDir dir;
  const auto case_dir = dir / "case";
  auto r = runChordfit("make-valve --out " + quoted(case_dir) + " --edge 2.0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = runChordfit("validate " + quoted(case_dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("leaflets:  2 (anterior"), std::string::npos) << r.out;

  r = runChordfit("heuristic " + quoted(case_dir) + " --out " + quoted(dir / "cords.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("anterior/anterolateral"), std::string::npos) << r.out;
  Diagnostics diagnostics;
  CordSet cords;
  ASSERT_TRUE(readCordSet(dir / "cords.json", "cords.json", cords, diagnostics));
  EXPECT_EQ(cords.tips.size(), 2u);
  EXPECT_GT(cords.cords.size(), 10u);
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().string().find(".chordfit-tmp."), std::string::npos)
        << "left a temp file";
  }

  r = runChordfit("metrics " + quoted(case_dir) + " --mesh " + quoted(case_dir / "open.ply") +
                  " --out " + quoted(dir / "metrics.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| Case | Area (mm²) | MinD (mm) | MedD (mm) | MaxD (mm) | AvgD (mm)"),
            std::string::npos)
      << r.out;
  const auto metrics = nlohmann::json::parse(testing::readText(dir / "metrics.json"));
  for (const char* key : {"min_mm", "median_mm", "max_mm", "mean_mm", "sd_mm", "area_mm2",
                          "prolapse_segments", "prolapse_max_height_mm"}) {
    EXPECT_TRUE(metrics.contains(key)) << key;
  }
  EXPECT_TRUE(metrics["prolapse_segments"].is_array());
  EXPECT_GT(metrics["area_mm2"].get<double>(), 500.0);
}

TEST(ChordfitCli, AFileOutputThatIsADirectoryIsRefusedBeforeTheWork) {
  // metrics --out and heuristic --out name files; an existing directory there (in the current
  // directory too, which has no parent to check) used to fail only at the final rename, exit 1.
  TempDir dir;
  const std::string example = std::string(CHORDFIT_SOURCE_DIR) + "/docs/example-case";
  std::filesystem::create_directory(dir / "taken.json");
  for (const std::string& command :
       {"metrics '" + example + "' --mesh '" + example + "/open.obj' --out taken.json",
        "heuristic '" + example + "' --out taken.json"}) {
    const auto run =
        testing::runProgram("/bin/sh", "-c \"cd " + quoted(dir.path()) + " && " +
                                           quoted(CHORDFIT_EXE) + " " + command + "\"");
    EXPECT_EQ(run.exit_code, 2) << command << "\n" << run.err;
    EXPECT_NE(run.err.find("--out: taken.json: is a directory"), std::string::npos) << run.err;
    EXPECT_EQ(run.out, "") << "no work before the check";
  }
  // Where no file can be created, even by root (access(W_OK) said yes there).
  const auto r = runChordfit("heuristic '" + example + "' --out /proc/chordfit-cords.json");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--out: /proc/chordfit-cords.json: no file can be created in /proc"),
            std::string::npos)
      << r.err;
  // A path ending in '/' names a directory, even one that does not exist yet.
  const auto slash = runChordfit("heuristic '" + example + "' --out " + quoted(dir / "new") + "/");
  EXPECT_EQ(slash.exit_code, 2) << slash.err;
  EXPECT_NE(slash.err.find("ends in a separator, which names a directory (none is there); "
                           "give the file to write"),
            std::string::npos)
      << slash.err;
}

TEST(ChordfitCli, AFineParametricValveGetsAStepCapItsRampFitsUnder) {
  // At edge 0.25 mm the automatic time step makes the 10 ms ramp ~7,000 steps, more than the
  // default cap: the case written must still be one validate and simulate accept.
  TempDir dir;
  const auto made = runChordfit("make-valve --edge 0.25 --out " + quoted(dir / "fine"));
  ASSERT_EQ(made.exit_code, 0) << made.err;
  EXPECT_NE(made.err.find("note: simulation.max_steps = "), std::string::npos) << made.err;
  const auto r = runChordfit("validate " + quoted(dir / "fine"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  // The default valve keeps the default cap (no simulation block).
  ASSERT_EQ(runChordfit("make-valve --out " + quoted(dir / "default")).exit_code, 0);
  EXPECT_EQ(testing::readText(dir / "default" / "case.json").find("simulation"), std::string::npos);
}

TEST(ChordfitCli, AnUnknownCommandIsNamed) {
  const auto r = runChordfit("simulat cases/x --out y");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("\"simulat\" is not a chordfit command (validate, "), std::string::npos)
      << r.err;
}

TEST(ChordfitCli, ValidatesTheDocumentedExampleCase) {
  const auto r =
      runChordfit(std::string("validate '") + CHORDFIT_SOURCE_DIR + "/docs/example-case'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("tracings:  3 polylines, 10 points"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("4 cords on 2 tips"), std::string::npos) << r.out;
}

TEST(ChordfitCli, MetricsOfTheExampleCaseMatchItsTracings) {
  const std::string example = std::string(CHORDFIT_SOURCE_DIR) + "/docs/example-case";
  const auto r = runChordfit("metrics '" + example + "' --mesh '" + example + "/open.obj'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // 10 tracing points; the row has numbers, and no prolapse on either side -> reconstructed.
  EXPECT_NE(r.out.find("| example-cone | 432 |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| Yes (none) |"), std::string::npos) << r.out;
}

// The metrics take the leaflets' thickness from the case's settings: a bad block is refused
// as by the commands that simulate (it gave "leaflets ± 0 mm" and exit 0).
TEST(ChordfitCli, MetricsRefuseABadSimulationBlock) {
  TempDir dir;
  const std::filesystem::path example =
      std::filesystem::path(CHORDFIT_SOURCE_DIR) / "docs" / "example-case";
  std::filesystem::copy(example, dir / "case", std::filesystem::copy_options::recursive);
  nlohmann::json j = nlohmann::json::parse(testing::readText(dir / "case" / "case.json"));
  j["simulation"] = {{"thickness_mm", 0}};
  testing::writeText(dir / "case" / "case.json", j.dump(2));
  const auto r = runChordfit("metrics " + quoted(dir / "case") + " --mesh " +
                             quoted(dir / "case" / "open.obj"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("simulation.thickness_mm"), std::string::npos) << r.err;
}

// A tracing drawn in another tool: the example case's commissural tracing as a Slicer legacy
// .fcsv in RAS and as a plain CSV gives the same metrics as the markups JSON.
TEST(ChordfitCli, TracingFilesInFcsvOrCsvGiveTheSameMetrics) {
  TempDir dir;
  const std::filesystem::path example =
      std::filesystem::path(CHORDFIT_SOURCE_DIR) / "docs" / "example-case";
  Diagnostics diagnostics;
  Curve curve;
  ASSERT_TRUE(readCurve(example / "tracing_commissural.mrk.json", curve, diagnostics));
  std::string fcsv =
      "# Markups fiducial file version = 4.13\n# CoordinateSystem = RAS\n"
      "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID\n";
  std::string csv = "label,x,y,z\n";
  for (Eigen::Index i = 0; i < curve.points.rows(); ++i) {
    const Eigen::Vector3d p = curve.points.row(i);
    fcsv += std::to_string(i) + "," + std::to_string(-p.x()) + "," + std::to_string(-p.y()) + "," +
            std::to_string(p.z()) + ",0,0,0,1,1,1,0,T-" + std::to_string(i) + ",,\n";
    csv += "T-" + std::to_string(i) + "," + std::to_string(p.x()) + "," + std::to_string(p.y()) +
           "," + std::to_string(p.z()) + "\n";
  }
  const auto reference =
      runChordfit("metrics " + quoted(example) + " --mesh " + quoted(example / "open.obj"));
  ASSERT_EQ(reference.exit_code, 0) << reference.err;
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"tracing_commissural.fcsv", fcsv}, {"tracing_commissural.csv", csv}}) {
    const auto case_dir = dir / name.substr(name.rfind('.') + 1);
    std::filesystem::copy(example, case_dir);
    testing::writeText(case_dir / name, text);
    std::string tracings = testing::readText(case_dir / "tracings.json");
    const std::string json_name = "tracing_commissural.mrk.json";
    tracings.replace(tracings.find(json_name), json_name.size(), name);
    testing::writeText(case_dir / "tracings.json", tracings);
    std::filesystem::remove(case_dir / json_name);
    const auto r =
        runChordfit("metrics " + quoted(case_dir) + " --mesh " + quoted(case_dir / "open.obj"));
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
    EXPECT_EQ(r.out, reference.out) << name;
  }
}

TEST(ChordfitCli, MakeValveAcceptsAUserAnnulusPolyline) {
  TempDir dir;
  Eigen::MatrixXd ring(48, 3);
  for (int i = 0; i < 48; ++i) {
    const double phi = 2.0 * M_PI * i / 48;
    ring.row(i) << 13.0 * std::cos(phi), 16.0 * std::sin(phi), 2.0 * std::cos(2 * phi);
  }
  writePointList(dir / "annulus.json", ring, true);
  auto r = runChordfit("make-valve --out " + quoted(dir / "case") + " --annulus " +
                       quoted(dir / "annulus.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(runChordfit("validate " + quoted(dir / "case")).exit_code, 0);
  // The valve's annulus is the given 26 x 32 mm saddle, not the default 28 x 35 mm ellipse:
  // every ring vertex within half a millimetre of the polyline.
  Diagnostics diagnostics;
  const std::optional<ValveCase> made = loadCase(dir / "case", diagnostics);
  ASSERT_TRUE(made.has_value());
  for (Eigen::Index k = 0; k < made->mesh.annulus.size(); ++k) {
    const Eigen::RowVector3d v = made->mesh.V.row(made->mesh.annulus(k));
    double nearest = INFINITY;
    for (Eigen::Index i = 0; i < ring.rows(); ++i) {
      const Eigen::RowVector3d a = ring.row(i), b = ring.row((i + 1) % ring.rows());
      const double t = std::clamp((v - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      nearest = std::min(nearest, (v - (a + t * (b - a))).norm());
    }
    EXPECT_LT(nearest, 0.5) << "ring vertex " << k;
  }
}

// An annulus in micrometres or metres is refused at once, naming the file's points and its
// span: it was meshed first (10^5 times the vertices in micrometres, until memory ran out).
TEST(ChordfitCli, MakeValveRefusesAUserAnnulusInOtherUnitsBeforeMeshing) {
  TempDir dir;
  for (const double unit : {1000.0, 0.001}) {
    Eigen::MatrixXd ring(40, 3);
    for (int i = 0; i < 40; ++i) {
      const double phi = 2.0 * M_PI * i / 40;
      ring.row(i) << 14.0 * std::cos(phi), 17.5 * std::sin(phi), 2.5 * std::cos(2 * phi);
    }
    ring *= unit;
    writePointList(dir / "annulus.json", ring, true);
    const auto r = runChordfit("make-valve --out " + quoted(dir / "case") + " --annulus " +
                               quoted(dir / "annulus.json"));
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    const std::string file = (dir / "annulus.json").string();
    EXPECT_NE(r.err.find("error: " + file + ": points: the annulus spans "), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("coordinates must be in millimetres (accepted: 2 to 150 mm)"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "case"));
  }
}

// A make-case case (normal-1, coarse, two planes) in `case_dir`: a directory holding an earlier
// chordfit case, its truth included.
void makeCoarseCase(const std::filesystem::path& case_dir) {
  const auto r = runChordfit("make-case --preset normal-1 --edge 3.0 --planes 2 --quiet --out " +
                             quoted(case_dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

// make-valve into a directory holding a case used to replace case.json and leave the earlier
// case's tracings, cords and truth beside it, describing another valve. Now it publishes as
// every command does: the files an earlier chordfit run wrote there and the new case lacks go,
// the user's own stay.
TEST(ChordfitCli, MakeValveOverAnEarlierCaseRemovesWhatTheNewCaseLacksAndKeepsTheUsersFiles) {
  TempDir dir;
  const auto case_dir = dir / "case";
  ASSERT_NO_FATAL_FAILURE(makeCoarseCase(case_dir));
  ASSERT_TRUE(std::filesystem::exists(case_dir / "truth" / "case" / "case.json"));
  auto r = runChordfit("heuristic " + quoted(case_dir) + " --out " +
                       quoted(case_dir / "heuristic_cords.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  testing::writeText(case_dir / "notes.txt", "the user's");

  r = runChordfit("make-valve --edge 3.0 --out " + quoted(case_dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("wrote " + (case_dir / "case.json").string() +
                       ", open.ply, leaflets.json, annulus_ring.json, annulus_closed.json; "
                       "removed tracings.json, cords.json, truth/cords.json, "),
            std::string::npos)
      << r.out;
  for (const char* stale : {"tracings.json", "cords.json", "truth"})
    EXPECT_FALSE(std::filesystem::exists(case_dir / stale)) << stale;
  EXPECT_TRUE(std::filesystem::exists(case_dir / "heuristic_cords.json"));
  EXPECT_EQ(testing::readText(case_dir / "notes.txt"), "the user's");
  r = runChordfit("validate " + quoted(case_dir));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("parametric-mitral"), std::string::npos) << r.out;
}

// A file the user wrote over a name a staged run had published (heuristic --out cords.json
// in a make-case directory) is the user's now: a later make-valve there keeps it.
TEST(ChordfitCli, MakeValveKeepsACordSetTheUserWroteOverTheCasesOwn) {
  TempDir dir;
  const auto case_dir = dir / "case";
  ASSERT_NO_FATAL_FAILURE(makeCoarseCase(case_dir));
  auto r = runChordfit("heuristic " + quoted(case_dir) + " --primary-spacing 5 --out " +
                       quoted(case_dir / "cords.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string users = testing::readText(case_dir / "cords.json");
  r = runChordfit("make-valve --edge 3.0 --out " + quoted(case_dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.find("removed tracings.json, cords.json,"), std::string::npos) << r.out;
  ASSERT_TRUE(std::filesystem::exists(case_dir / "cords.json"));
  EXPECT_EQ(testing::readText(case_dir / "cords.json"), users);
  EXPECT_FALSE(std::filesystem::exists(case_dir / "tracings.json")) << "the earlier case's";
}

// A dangling link where make-case's truth/ goes: refused before any work, the directory as
// it was (it failed after the case's files had been replaced).
TEST(ChordfitCli, MakeCaseRefusesADanglingLinkWhereTheTruthGoes) {
  TempDir dir;
  const auto case_dir = dir / "case";
  std::filesystem::create_directories(case_dir);
  testing::writeText(case_dir / "case.json", "the user's");
  std::filesystem::create_symlink(dir / "nowhere", case_dir / "truth");
  const auto r = runChordfit("make-case --preset normal-1 --edge 5 --planes 2 --quiet --out " +
                             quoted(case_dir));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("in the way of an output directory"), std::string::npos) << r.err;
  EXPECT_EQ(testing::readText(case_dir / "case.json"), "the user's");
}

// A directory that is not a case: what a case is and how to make one, not "file not found".
TEST(ChordfitCli, ValidateOfADirectoryWithoutCaseJsonSaysWhatACaseIs) {
  TempDir dir;
  const auto r = runChordfit("validate " + quoted(dir.path()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(
      r.err.find((dir / "case.json").string() + ": not found: a case directory holds case.json"),
      std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("make-valve, import-mesh or make-case"), std::string::npos) << r.err;
}

// A case name titles figures and table rows: make-valve wrote a case validate then refused
// (a newline in --name) or one with an empty Case cell (--name ""), and exited 0. Refused
// before anything is written, as import-mesh refuses them (test_case_import.cpp).
TEST(ChordfitCli, MakeValveRefusesANameWithAControlCharacterOrABlankOne) {
  TempDir dir;
  for (const auto& [name, message] : std::vector<std::pair<std::string, std::string>>{
           {"\"$(printf 'a\\nb')\"",
            "error: make-valve: --name: contains a control character (a newline, tab or NUL): "
            "give a name of printable characters\n"},
           {"''", "error: make-valve: --name: is blank: give the case a name"},
           {"'  '", "error: make-valve: --name: is blank"}}) {
    const auto r =
        runChordfit("make-valve --edge 3 --out " + quoted(dir / "case") + " --name " + name);
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.out;
    EXPECT_NE(r.err.find(message), std::string::npos) << name << ": " << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "case")) << name;
  }
}

// A blank "name" in case.json gave the same empty cell.
TEST(ChordfitCli, ValidateRefusesABlankCaseName) {
  TempDir dir;
  ASSERT_EQ(runChordfit("make-valve --edge 3 --out " + quoted(dir / "case")).exit_code, 0);
  std::string text = testing::readText(dir / "case" / "case.json");
  const std::string named = "\"name\": \"parametric-mitral\"";
  ASSERT_NE(text.find(named), std::string::npos) << text;
  text.replace(text.find(named), named.size(), "\"name\": \" \"");
  testing::writeText(dir / "case" / "case.json", text);
  const auto r = runChordfit("validate " + quoted(dir / "case"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: case.json: name: is blank: give the case a name"), std::string::npos)
      << r.err;
}

TEST(ChordfitCli, RejectsANonsenseEdgeLengthWithExitCodeTwo) {
  TempDir dir;
  const auto r = runChordfit("make-valve --out " + quoted(dir / "case") + " --edge -1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: "), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "case" / "case.json"));
}

TEST(ChordfitCli, MakeValveTakesTheAnatomyAndNamesABadValue) {
  TempDir dir;
  auto r = runChordfit("make-valve --out " + quoted(dir / "tall") +
                       " --edge 3 --posterior-height 17 --anterior-height 26");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = runChordfit("make-valve --out " + quoted(dir / "normal") + " --edge 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Taller leaflets: more leaflet area on the same annulus.
  const auto area = [&](const std::string& name) {
    Diagnostics diagnostics;
    const std::optional<ValveCase> c = loadCase(dir / name, diagnostics);
    EXPECT_TRUE(c.has_value()) << name;
    return c ? surfaceArea(c->mesh.V, c->mesh.F) : 0.0;
  };
  EXPECT_GT(area("tall"), 1.05 * area("normal"));
  EXPECT_EQ(r.err.find("note: make-valve"), std::string::npos) << "the default anatomy: " << r.err;
  // Made as asked, with a note, when unlike an adult mitral valve.
  r = runChordfit("make-valve --out " + quoted(dir / "odd") +
                  " --edge 3 --ap 40 --cc 30 --commissural-height 24");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: make-valve: the commissures (24 mm, --commissural-height) are as "
                       "tall as the anterior leaflet"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("note: make-valve: --ap / --cc = 1.33"), std::string::npos) << r.err;
  r = runChordfit("make-valve --out " + quoted(dir / "bad") + " --posterior-side-height -1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: make-valve: --posterior-side-height: must be positive"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad" / "case.json"));
}

// --cc 10 lowers the saddle heights' bound to 5 mm; the message used to blame only
// --closed-saddle's default 7, an option the user never gave.
TEST(ChordfitCli, MakeValveNamesTheDiametersThatBoundTheSaddleHeights) {
  TempDir dir;
  const auto r = runChordfit("make-valve --cc 10 --ap 40 --out " + quoted(dir / "case"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: make-valve: --closed-saddle: must be in [0, 5] (half the smaller "
                       "of --ap 40 and --cc 10), got 7"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "case" / "case.json"));
}

// A leaflet height within its range (positive, finite) but far below the mesh's edge made
// zero-area triangles: make-valve wrote a case that validate, simulate and fit then refused.
// The case is read back before it is published; an existing directory is left as it was.
TEST(ChordfitCli, MakeValveWritesNoCaseThatWouldNotValidate) {
  TempDir dir;
  auto r = runChordfit("make-valve --out " + quoted(dir / "flat") + " --anterior-height 1e-300");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: make-valve: the case these options make (--anterior-height "
                       "1e-300) would not validate, so it was not written"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("error: open.ply: face "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("degenerate triangle (zero area)"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "flat")) << "created for nothing";
  // Over an earlier case: that case stays, file for file.
  ASSERT_EQ(runChordfit("make-valve --edge 3 --out " + quoted(dir / "kept")).exit_code, 0);
  const std::string before = testing::readText(dir / "kept" / "open.ply");
  r = runChordfit("make-valve --out " + quoted(dir / "kept") + " --posterior-height 1e-300");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(testing::readText(dir / "kept" / "open.ply"), before);
  Diagnostics diagnostics;
  EXPECT_TRUE(loadCase(dir / "kept", diagnostics).has_value());
}

TEST(ChordfitCli, RejectsAMeshWhoseTopologyDiffersFromTheCase) {
  TempDir dir;
  writeCase(dir / "case", testing::tinyConeCase());
  runChordfit("make-valve --out " + quoted(dir / "other") + " --edge 3.0");
  const auto r = runChordfit("metrics " + quoted(dir / "case") + " --mesh " +
                             quoted(dir / "other" / "open.ply"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("does not have the case mesh's topology"), std::string::npos) << r.err;
}

// One vertex of a closed mesh thrown far away: named, not every other triangle called
// degenerate (triangle areas are judged against the mesh's size).
TEST(ChordfitCli, NamesTheFarVertexOfAClosedMeshBeforeJudgingItsTriangles) {
  TempDir dir;
  ValveCase valve = testing::tinyConeCase();
  writeCase(dir / "case", valve);
  valve.mesh.V(5, 0) = 1e9;
  writePly(dir / "far.ply", valve.mesh.V, valve.mesh.F);
  const auto r =
      runChordfit("metrics " + quoted(dir / "case") + " --mesh " + quoted(dir / "far.ply"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("vertices[5]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("from the valve mesh"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("degenerate"), std::string::npos) << r.err;
}

// The same counts but one triangle's corners in another order: named, not "topology (161 /
// 254 vs 161 / 254)".
TEST(ChordfitCli, NamesTheFirstTriangleThatDiffersFromTheCaseMesh) {
  TempDir dir;
  ValveCase valve = testing::tinyConeCase();
  writeCase(dir / "case", valve);
  std::swap(valve.mesh.F(3, 0), valve.mesh.F(3, 2));
  writePly(dir / "flipped.ply", valve.mesh.V, valve.mesh.F);
  const auto r =
      runChordfit("metrics " + quoted(dir / "case") + " --mesh " + quoted(dir / "flipped.ply"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("flipped.ply: faces[3]: vertices "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("must keep the case mesh's triangles in their order"), std::string::npos)
      << r.err;
}

TEST(ChordfitCli, HeuristicRejectsANonPositiveSpacingOrDepth) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  for (const std::string option :
       {"--primary-spacing -1", "--secondary-spacing 0", "--secondary-depth -3"}) {
    const auto r = runChordfit("heuristic " + quoted(small) + " " + option + " --out " +
                               quoted(dir / "cords.json"));
    EXPECT_EQ(r.exit_code, 2) << option;
    EXPECT_NE(r.err.find("error: heuristic: " + option.substr(0, option.find(' '))),
              std::string::npos)
        << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "cords.json"));
}

// "27 cords on 1 PM tips": a case whose pm_tips has one tip.
TEST(ChordfitCli, HeuristicCountsOnePmTipInTheSingular) {
  TempDir dir;
  const auto case_dir = dir / "case";
  ASSERT_EQ(runChordfit("make-valve --edge 3 --out " + quoted(case_dir)).exit_code, 0);
  nlohmann::json c = nlohmann::json::parse(testing::readText(case_dir / "case.json"));
  c["pm_tips"] = "pm_tips.json";
  testing::writeText(case_dir / "case.json", c.dump(2));
  testing::writeText(case_dir / "pm_tips.json",
                     R"({"tips": [{"name": "single", "position": [0, 0, -20]}]})");
  const auto r = runChordfit("heuristic " + quoted(case_dir) + " --out " + quoted(dir / "h.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::regex line("heuristic cord set: [0-9]+ cords on 1 PM tip -> ");
  EXPECT_TRUE(std::regex_search(r.out, line)) << r.out;
}

// A tracing repeated point for point (a file pasted twice) counts its points twice and narrows
// the fit's SDs by about sqrt(2): validate and fit say so (it was accepted without a word).
TEST(ChordfitCli, ValidateAndFitNoteTracingsRepeatedPointForPoint) {
  TempDir dir;
  const auto case_dir = dir / "case";
  std::filesystem::copy(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal", case_dir,
                        std::filesystem::copy_options::recursive);
  nlohmann::json c = nlohmann::json::parse(testing::readText(case_dir / "case.json"));
  const auto tracings_file = case_dir / c["tracings"].get<std::string>();
  nlohmann::json tracings = nlohmann::json::parse(testing::readText(tracings_file));
  const std::size_t n = tracings["tracings"].size();
  ASSERT_GE(n, 2u);
  tracings["tracings"].push_back(tracings["tracings"][1]);
  testing::writeText(tracings_file, tracings.dump());
  const std::string note = "note: tracings[" + std::to_string(n) +
                           "] repeats tracings[1] point for point: its points count again";
  auto r = runChordfit("validate " + quoted(case_dir));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(note), std::string::npos) << r.err;
  r = runChordfit("fit " + quoted(case_dir) + " --max-sims 2 --no-uncertainty --quiet --out " +
                  quoted(dir / "fit"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(note), std::string::npos) << r.err;
  // The bundled case has none.
  r = runChordfit("validate " + quoted(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal"));
  EXPECT_EQ(r.err.find("repeats tracings"), std::string::npos) << r.err;
}

// Leaflet labels swapped (1 - label) pass every check of the case and made a fit end at AvgD
// 2.23 instead of 0.42 mm on this case: every command reading the case warns and goes on.
TEST(ChordfitCli, SwappedLeafletLabelsAreWarnedAboutByEveryCommandReadingTheCase) {
  TempDir dir;
  const auto case_dir = dir / "case";
  std::filesystem::copy(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal", case_dir,
                        std::filesystem::copy_options::recursive);
  const auto labels_file = case_dir / "leaflets.json";
  nlohmann::json labels = nlohmann::json::parse(testing::readText(labels_file));
  for (auto& label : labels["labels"]) label = 1 - label.get<int>();
  testing::writeText(labels_file, labels.dump());
  const std::string warning = "warning: case " + case_dir.string() +
                              ": only 26 % of the tracing "
                              "points lie nearest an open-state vertex of their own leaflet";
  for (const std::string& command :
       {"validate " + quoted(case_dir),
        "simulate " + quoted(case_dir) + " --quiet --out " + quoted(dir / "sim"),
        // Once, though the fit reads the case again for its fitted closure.
        "fit " + quoted(case_dir) + " --max-sims 2 --no-uncertainty --quiet --out " +
            quoted(dir / "fit")}) {
    const auto r = runChordfit(command);
    EXPECT_EQ(r.exit_code, 0) << command << "\n" << r.err;
    EXPECT_EQ(testing::occurrences(r.err, warning), 1u) << command << "\n" << r.err;
  }
  // The bundled case, correctly labelled (74 %), gets none.
  const auto r =
      runChordfit("validate " + quoted(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal"));
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
}

// With the case's own cords, the heuristic takes each cord-set tip's position from the pm_tips
// tip in the same place in the list; with another count it ignored pm_tips without a word.
TEST(ChordfitCli, HeuristicRefusesPmTipsItCannotPairWithTheCasesCords) {
  TempDir dir;
  const auto case_dir = dir / "case";
  std::filesystem::copy(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal", case_dir,
                        std::filesystem::copy_options::recursive);
  nlohmann::json c = nlohmann::json::parse(testing::readText(case_dir / "case.json"));
  c["pm_tips"] = "pm_tips.json";
  testing::writeText(case_dir / "case.json", c.dump(2));
  testing::writeText(case_dir / "pm_tips.json", R"({"tips": [
      {"name": "anterolateral", "position": [0, 6, -22]},
      {"name": "posteromedial", "position": [0, -7, -22]},
      {"name": "third", "position": [3, 0, -24]}]})");
  auto r = runChordfit("heuristic " + quoted(case_dir) + " --out " + quoted(dir / "h.json"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("error: heuristic: " + case_dir.string() +
                       ": pm_tips: 3 PM tips for the cord set's 2 tips"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "h.json"));
  // Two: used, in the cord set's order.
  testing::writeText(case_dir / "pm_tips.json", R"({"tips": [
      {"name": "anterolateral", "position": [0, 6, -22]},
      {"name": "posteromedial", "position": [0, -7, -22]}]})");
  r = runChordfit("heuristic " + quoted(case_dir) + " --out " + quoted(dir / "h.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Diagnostics diagnostics;
  CordSet set;
  ASSERT_TRUE(readCordSet(dir / "h.json", "h.json", set, diagnostics));
  ASSERT_EQ(set.tips.size(), 2u);
  EXPECT_EQ(set.tips[1].position, Eigen::Vector3d(0, -7, -22));
}

// --secondary-spacing 1e-9 used to take 21 GB and --primary-spacing 1e-8 to place 1 cord
// (the count overflowed an int); spacings below 0.1 mm are refused before the case is read.
TEST(ChordfitCli, HeuristicRefusesASpacingBelowATenthOfAMillimetre) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  for (const std::string option :
       {"--primary-spacing 1e-08", "--secondary-spacing 1e-09", "--secondary-spacing 0.09"}) {
    const auto r = runChordfit("heuristic " + quoted(small) + " " + option + " --out " +
                               quoted(dir / "cords.json"));
    EXPECT_EQ(r.exit_code, 2) << option << ": " << r.err;
    const std::string name = option.substr(0, option.find(' '));
    const std::string value = option.substr(option.find(' ') + 1);
    EXPECT_NE(r.err.find("error: heuristic: " + name + ": must be at least 0.1 mm"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("got " + value), std::string::npos) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "cords.json"));
}

// Placement options that change nothing say so: on a case with its own cords (their insertions
// are kept), and a secondary depth no vertex reaches (no secondaries at all).
TEST(ChordfitCli, HeuristicSaysWhenItsPlacementOptionsPlaceNothing) {
  TempDir dir;
  const auto small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  auto r = runChordfit("heuristic " + quoted(small) + " --primary-spacing 10 --out " +
                       quoted(dir / "kept.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: heuristic: the case's own cords keep their insertions"),
            std::string::npos)
      << r.err;
  ASSERT_EQ(runChordfit("make-valve --out " + quoted(dir / "valve") + " --edge 3").exit_code, 0);
  r = runChordfit("heuristic " + quoted(dir / "valve") + " --secondary-depth 100 --out " +
                  quoted(dir / "deep.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: heuristic: no secondary cord placed"), std::string::npos) << r.err;
  // Spacings wider than the posterior free edge: two cords, both anterior and on one side; the
  // other tip used to be printed at the annulus centre without a word.
  ASSERT_EQ(runChordfit("make-valve --out " + quoted(dir / "valve2") + " --edge 2").exit_code, 0);
  r = runChordfit("heuristic " + quoted(dir / "valve2") +
                  " --primary-spacing 60 --secondary-spacing 60 --out " +
                  quoted(dir / "wide.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: heuristic: the posterior leaflet gets no cord at --primary-spacing "
                       "60 mm and --secondary-spacing 60 mm: nothing holds it down in systole"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("note: heuristic: tip posteromedial carries no cord (none of the cords "
                       "lies on its side), so its position"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("anterior leaflet gets no cord"), std::string::npos) << r.err;
  r = runChordfit("heuristic " + quoted(dir / "valve") + " --out " + quoted(dir / "plain.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("note:"), std::string::npos) << r.err;
}

// --out "" used to mean the current directory: make-valve wrote there and printed
// "wrote /case.json"; simulate, fit, sweep-cord and compare did all the work and then failed
// to create "" (exit 1).
TEST(ChordfitCli, AnEmptyOutIsRefusedBeforeTheWorkByEveryCommand) {
  const auto example_dir = std::filesystem::path(CHORDFIT_SOURCE_DIR) / "docs" / "example-case";
  const std::string example = quoted(example_dir);
  const std::string cords = quoted(example_dir / "cords.json");
  const std::string mesh = quoted(example_dir / "open.obj");
  const std::pair<std::string, std::string> commands[] = {
      {"make-valve", ""},
      {"import-mesh", mesh + " --landmarks " + cords},
      {"heuristic", example},
      {"edit-cords", example},
      {"metrics", example + " --mesh " + mesh},
      {"simulate", example},
      {"sweep-cord", example},
      {"make-case", "--preset normal"},
      {"fit", example},
      {"compare", example + " " + cords}};
  for (const auto& [command, arguments] : commands) {
    const auto r = runChordfit(command + " " + arguments + " --out ''");
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    EXPECT_NE(r.err.find("error: " + command + ": --out: must not be empty"), std::string::npos)
        << command << ": " << r.err;
    EXPECT_EQ(r.out, "") << command << ": no work before the check";
  }
}

// An --out that is (or passes through) a symbolic link to nowhere used to fail after the work
// (exit 1) for a directory, and for a file to replace the link instead of writing its target.
TEST(ChordfitCli, AnOutThroughADanglingSymbolicLinkIsRefusedBeforeTheWork) {
  TempDir dir;
  const std::string example =
      quoted(std::filesystem::path(CHORDFIT_SOURCE_DIR) / "docs" / "example-case");
  std::filesystem::create_symlink(dir / "missing", dir / "link");
  const std::string problem = (dir / "link").string() + " is a symbolic link to " +
                              (dir / "missing").string() + ", which does not exist";
  for (const std::string& command : {"simulate " + example + " --out " + quoted(dir / "link"),
                                     "make-valve --out " + quoted(dir / "link" / "case"),
                                     "heuristic " + example + " --out " + quoted(dir / "link")}) {
    const auto r = runChordfit(command);
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    EXPECT_NE(r.err.find(": --out: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(problem), std::string::npos) << command << ": " << r.err;
    EXPECT_EQ(r.out, "") << command << ": no work before the check";
  }
  EXPECT_TRUE(std::filesystem::is_symlink(dir / "link")) << "the link is left alone";
  EXPECT_FALSE(std::filesystem::exists(dir / "missing"));
}

// An --out that names a device or FIFO is refused: the atomic write's rename would replace the
// node itself (as root, `heuristic --out /dev/null` would have replaced the system's).
TEST(ChordfitCli, AnOutThatIsADeviceOrFifoIsRefusedAndLeftAlone) {
  TempDir dir;
  const std::string example =
      quoted(std::filesystem::path(CHORDFIT_SOURCE_DIR) / "docs" / "example-case");
  ASSERT_EQ(::mkfifo((dir / "pipe").c_str(), 0600), 0);
  std::filesystem::create_directory(dir / "sim");
  ASSERT_EQ(::mkfifo((dir / "sim" / "closed.ply").c_str(), 0600), 0);
  for (const std::string& command :
       {"heuristic " + example + " --out " + quoted(dir / "pipe"),
        "metrics " + example + " --mesh " + example + "/open.obj --out " + quoted(dir / "pipe"),
        "simulate " + example + " --out " + quoted(dir / "sim")}) {
    const auto r = runChordfit(command);
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    EXPECT_NE(r.err.find("is not a regular file (a device, FIFO or socket)"), std::string::npos)
        << command << ": " << r.err;
  }
  EXPECT_TRUE(std::filesystem::is_fifo(dir / "pipe"));
  EXPECT_TRUE(std::filesystem::is_fifo(dir / "sim" / "closed.ply"));
}

// case.json with an unknown key nested 100,000 levels deep: refused by the case's validation
// (exit 2) in every command, not a stack overflow in the check of --out against the inputs.
TEST(ChordfitCli, ADeeplyNestedCaseFileIsRefusedNotACrash) {
  TempDir dir;
  const auto example = std::filesystem::path(CHORDFIT_SOURCE_DIR) / "docs" / "example-case";
  std::filesystem::copy(example, dir / "case", std::filesystem::copy_options::recursive);
  auto json = nlohmann::json::parse(testing::readText(dir / "case" / "case.json"));
  std::string text = json.dump();
  text.pop_back();  // the closing brace
  text += ",\"x\":" + std::string(100000, '[') + std::string(100000, ']') + "}";
  testing::writeText(dir / "case" / "case.json", text);
  for (const std::string& command :
       {"heuristic " + quoted(dir / "case") + " --out " + quoted(dir / "h.json"),
        "simulate " + quoted(dir / "case") + " --out " + quoted(dir / "sim")}) {
    const auto r = runChordfit(command);
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    EXPECT_NE(r.err.find("x: unknown key"), std::string::npos) << command << ": " << r.err;
  }
}

// (An unknown command: AnUnknownCommandIsNamed.) A missing argument or command is named.
TEST(ChordfitCli, UnknownCommandsAndMissingArgumentsAreUsageErrors) {
  const auto no_case = runChordfit("heuristic");
  EXPECT_EQ(no_case.exit_code, 2);
  EXPECT_NE(no_case.err.find("heuristic"), std::string::npos) << no_case.err;
  EXPECT_NE(no_case.err.find("CASE_DIR"), std::string::npos) << no_case.err;
  EXPECT_NE(no_case.err.find("required"), std::string::npos) << no_case.err;
  const auto no_out =
      runChordfit("fit " + quoted(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal"));
  EXPECT_EQ(no_out.exit_code, 2);
  EXPECT_NE(no_out.err.find("error: fit: --out: required"), std::string::npos) << no_out.err;
  const auto no_command = runChordfit("");
  EXPECT_EQ(no_command.exit_code, 2);
  EXPECT_NE(no_command.err.find("a command is required"), std::string::npos) << no_command.err;
  const auto r = runChordfit("--help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("validate"), std::string::npos);
}

}  // namespace
}  // namespace chordfit
