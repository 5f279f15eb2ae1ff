// `chordfit validate` end to end: a good case passes with a summary; every kind of bad input
// named by the foundation issue gives "error: <file>: <where>: <problem>" and exit code 2.
#include <algorithm>
#include <cmath>
#include <functional>
#include <regex>
#include <sstream>
#include <string>
#include <utility>

#include <unistd.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/case_io.h"
#include "core/cordset_io.h"
#include "core/mesh_io.h"
#include "core/mesh_topology.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

using testing::runChordfit;
using testing::TempDir;
using testing::tinyConeCase;
using testing::writeText;

class ValidateCommand : public ::testing::Test {
 protected:
  void SetUp() override { writeCase(dir_.path(), valve_); }

  testing::CommandResult validate() {
    return runChordfit("validate '" + dir_.path().string() + "'");
  }

  // Asserts exit code 2, no crash, and an error line for `file` whose text matches `pattern`.
  void expectError(const std::string& file, const std::string& pattern) {
    const testing::CommandResult r = validate();
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    const std::regex line("(^|\n)error: " + file + ": [^\n]*" + pattern);
    EXPECT_TRUE(std::regex_search(r.err, line)) << "stderr was:\n" << r.err;
    EXPECT_EQ(r.err.find("terminate"), std::string::npos) << r.err;
  }

  // Writes `text` as the case's tracings.json and names it in case.json.
  void useTracings(const std::string& text) {
    writeText(dir_ / "tracings.json", text);
    editCaseJson([](nlohmann::json& j) { j["tracings"] = "tracings.json"; });
  }

  void editCaseJson(const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json j = nlohmann::json::parse(testing::readText(dir_ / "case.json"));
    edit(j);
    writeText(dir_ / "case.json", j.dump(2));
  }

  // `count` copies of one cord from the anterolateral tip at (0, 5, -20) to vertex 9, 20 mm at
  // rest (seed and fitted): a cord set the validator accepts, for a test to spoil.
  static CordSet cordsFromOneTip(int count) {
    CordSet set;
    set.tips.push_back({"anterolateral", Eigen::Vector3d(0, 5, -20), std::nullopt});
    Cord cord;
    cord.vertex = 9;
    cord.rest_length = cord.seed_rest_length = 20.0;
    set.cords.assign(count, cord);
    return set;
  }

  // Writes `set` as the case's cords.json and names it in case.json; `edit`, when given,
  // changes the written JSON first (for what a CordSet cannot hold: an unknown key, a number
  // out of range).
  void useCords(const CordSet& set, const std::function<void(nlohmann::json&)>& edit = nullptr) {
    writeCordSet(dir_ / "cords.json", set);
    if (edit) {
      nlohmann::json cords = nlohmann::json::parse(testing::readText(dir_ / "cords.json"));
      edit(cords);
      writeText(dir_ / "cords.json", cords.dump());
    }
    editCaseJson([](nlohmann::json& j) { j["cords"] = "cords.json"; });
  }

  TempDir dir_;
  ValveCase valve_ = tinyConeCase();
};

TEST_F(ValidateCommand, AcceptsAGoodCaseAndPrintsItsSummary) {
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("16 vertices, 16 triangles"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("anterior 6"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("posterior 10"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ring of 8 vertices"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("valid"), std::string::npos) << r.out;
}

// A missing file is named at the field that gives it, with the directory it was looked for
// in: "error: nope.ply: file not found" said neither which field nor where.
TEST_F(ValidateCommand, ReportsAMissingFileAtItsFieldWithTheDirectorySearched) {
  const std::string case_dir = std::filesystem::absolute(dir_.path()).lexically_normal().string();
  std::filesystem::remove(dir_ / "leaflets.json");
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: case.json: leaflets.labels: \"leaflets.json\": file not found in " +
                       case_dir + "\n"),
            std::string::npos)
      << r.err;
  writeCase(dir_.path(), valve_);
  editCaseJson([](nlohmann::json& j) { j["mesh"] = "nope.ply"; });
  expectError("case\\.json", "mesh: \"nope\\.ply\": file not found in /");
  editCaseJson([](nlohmann::json& j) {
    j["mesh"] = "open.ply";
    j["cords"] = "sub/cords.json";
  });
  expectError("case\\.json", "cords: \"sub/cords\\.json\": file not found in /");
  // A tracing's curve file, named in tracings.json.
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                                "file": "nope.csv"}]})");
  editCaseJson([](nlohmann::json& j) { j.erase("cords"); });
  expectError("tracings\\.json", "tracings\\[0\\]\\.file: \"nope\\.csv\": file not found in /");
  // A link to nothing is not "not found": the name is there.
  std::filesystem::create_symlink("gone.json", dir_ / "linked.json");
  editCaseJson([](nlohmann::json& j) {
    j.erase("tracings");
    j["pm_tips"] = "linked.json";
  });
  expectError("case\\.json", "pm_tips: \"linked\\.json\" is a symbolic link to nothing");
}

TEST_F(ValidateCommand, ReportsAMissingCaseDirectory) {
  const testing::CommandResult r = runChordfit("validate '" + (dir_ / "nowhere").string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("case directory not found"), std::string::npos) << r.err;
}

// A case directory that is a loop of links, or whose name is too long, is bad input said as
// such (exit 2), on every command that reads a case; it used to leave as an unexpected failure
// (exit 1, "filesystem error: status: ...").
TEST_F(ValidateCommand, SaysWhyACaseDirectoryThatIsALoopOfLinksCannotBeRead) {
  const std::filesystem::path loop = dir_ / "loop";
  std::filesystem::create_symlink("loop", loop);
  for (const std::string command : {"validate", "heuristic", "simulate", "fit", "sweep-cord"}) {
    const std::string out = command == "validate"    ? ""
                            : command == "heuristic" ? " --out x.json"
                                                     : " --out x";
    const testing::CommandResult r = runChordfit(command + " " + testing::quoted(loop) + out);
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    EXPECT_NE(r.err.find(loop.string() + ": cannot be read (Too many levels of symbolic links)"),
              std::string::npos)
        << command << ": " << r.err;
  }
  const std::string long_name = (dir_ / std::string(300, 'a')).string();
  const testing::CommandResult r = runChordfit("validate " + testing::quoted(long_name));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(": cannot be read (File name too long)"), std::string::npos) << r.err;
}

TEST_F(ValidateCommand, ReportsMalformedJsonWithLineAndColumn) {
  writeText(dir_ / "case.json", "{\n  \"version\": 1,\n  \"mesh\": \"open.ply\",,\n}");
  // The whole reason, not the part after its last ": " (which cut it to the last characters read).
  expectError("case\\.json",
              "line 3, column [0-9]+: malformed JSON: syntax error while parsing object key");
}

TEST_F(ValidateCommand, ReportsAWrongJsonType) {
  editCaseJson([](nlohmann::json& j) { j["mesh"] = 5; });
  expectError("case\\.json", "mesh: expected a string, got number");
}

TEST_F(ValidateCommand, ReportsAnUnknownFormatVersion) {
  editCaseJson([](nlohmann::json& j) { j["version"] = 7; });
  expectError("case\\.json", "version: unsupported format version 7");
}

TEST_F(ValidateCommand, ReportsAFaceIndexOutOfRange) {
  // Legacy VTK, parsed by our own reader, which leaves index checks to the validator.
  writeText(dir_ / "open.vtk",
            "# vtk DataFile Version 3.0\nbad\nASCII\nDATASET POLYDATA\nPOINTS 3 double\n"
            "0 0 0\n1 0 0\n0 1 0\nPOLYGONS 1 4\n3 0 1 99\n");
  editCaseJson([](nlohmann::json& j) { j["mesh"] = "open.vtk"; });
  expectError("open\\.vtk", "face 0: vertex index 99 out of range");
}

// CGAL refused an OBJ index past the vertex count with "could not parse the file".
TEST_F(ValidateCommand, ReportsAnObjFaceIndexOutOfRangeWithItsLineAndTheValidRange) {
  std::string obj;
  for (Eigen::Index i = 0; i < valve_.mesh.V.rows(); ++i)
    obj += "v " + std::to_string(valve_.mesh.V(i, 0)) + " " + std::to_string(valve_.mesh.V(i, 1)) +
           " " + std::to_string(valve_.mesh.V(i, 2)) + "\n";
  for (Eigen::Index f = 0; f < valve_.mesh.F.rows(); ++f)
    obj += "f " + std::to_string(valve_.mesh.F(f, 0) + 1) + " " +
           std::to_string(valve_.mesh.F(f, 1) + 1) + " " +
           std::to_string(f == 2 ? 99 : valve_.mesh.F(f, 2) + 1) + "\n";
  writeText(dir_ / "open.obj", obj);
  editCaseJson([](nlohmann::json& j) { j["mesh"] = "open.obj"; });
  expectError("open\\.obj",
              "line 19: face 2: vertex index 99 is out of range: the file has 16 vertices \\(1 to "
              "16, or -1 to -16 counting back\\)");
}

TEST_F(ValidateCommand, ReportsADegenerateTriangle) {
  valve_.mesh.V.row(8) = valve_.mesh.V.row(0);  // face 0 = (0, 1, 8) collapses
  writePly(dir_ / "open.ply", valve_.mesh.V, valve_.mesh.F);
  expectError("open\\.ply", "face 0: degenerate triangle");
}

TEST_F(ValidateCommand, ReportsANonManifoldEdge) {
  Eigen::MatrixXd V(valve_.mesh.V.rows() + 1, 3);
  V << valve_.mesh.V, 20.0, 20.0, 5.0;
  Eigen::MatrixXi F(valve_.mesh.F.rows() + 1, 3);
  F << valve_.mesh.F, 1, 8, 16;  // edge (1, 8) now has three triangles
  writePly(dir_ / "open.ply", V, F);
  expectError("open\\.ply", "edge \\(1, 8\\): non-manifold edge shared by 3 triangles");
}

// A vertex no triangle uses has no mass: held where it is, it would stop any sheet that comes
// near it, invisibly.
TEST_F(ValidateCommand, ReportsAVertexInNoTriangle) {
  Eigen::MatrixXd V(valve_.mesh.V.rows() + 1, 3);
  V << valve_.mesh.V, valve_.mesh.V.colwise().mean();
  writePly(dir_ / "open.ply", V, valve_.mesh.F);
  expectError("open\\.ply",
              "vertices\\[" + std::to_string(valve_.mesh.V.rows()) + "\\]: vertex in no triangle");
}

TEST_F(ValidateCommand, ReportsANaNCoordinate) {
  valve_.mesh.V(3, 1) = std::nan("");
  writePly(dir_ / "open.ply", valve_.mesh.V, valve_.mesh.F);
  expectError("open\\.ply", "vertex 3: coordinate y is NaN");
}

TEST_F(ValidateCommand, ReportsAnInfiniteCoordinate) {
  valve_.mesh.V(5, 2) = INFINITY;
  writePly(dir_ / "open.ply", valve_.mesh.V, valve_.mesh.F);
  expectError("open\\.ply", "vertex 5: coordinate z is infinite");
}

TEST_F(ValidateCommand, ReportsAnAnnulusRingThatIsNotAClosedBoundaryLoop) {
  // Skipping vertex 4 leaves a step 3 -> 5 that is no mesh edge.
  writeText(dir_ / "annulus_ring.json", R"({"vertices": [0, 1, 2, 3, 5, 6, 7]})");
  writeText(dir_ / "annulus_closed.json",
            nlohmann::json{{"points", nlohmann::json::array({{10, 0, 0},
                                                             {7, 7, 0},
                                                             {0, 10, 0},
                                                             {-7, 7, 0},
                                                             {-7, -7, 0},
                                                             {0, -10, 0},
                                                             {7, -7, 0}})}}
                .dump());
  expectError("annulus_ring\\.json", "vertices\\[3\\]->\\[4\\]: .*not a closed loop");
}

TEST_F(ValidateCommand, ReportsAnAnnulusRingOffTheBoundary) {
  // Every step is a mesh edge, but (1, 9) is a diagonal shared by two triangles.
  writeText(dir_ / "annulus_ring.json", R"({"vertices": [1, 9, 8, 0]})");
  writeText(dir_ / "annulus_closed.json", R"({"points": [[1,0,0],[0,1,0],[0,0,1],[1,1,1]]})");
  expectError("annulus_ring\\.json", "is not on the mesh boundary");
}

TEST_F(ValidateCommand, ReportsAClosedAnnulusCountThatDoesNotMatchTheRing) {
  writeText(dir_ / "annulus_closed.json", R"({"points": [[1,0,0],[0,1,0],[0,0,1]]})");
  expectError("annulus_closed\\.json", "3 closed-state annulus positions for an annulus ring of 8");
}

// The closed annulus in the reverse order of the ring, or collapsed to a point: both passed
// before and made the closure diverge (exit 3).
TEST_F(ValidateCommand, ReportsAClosedAnnulusRunningTheOtherWayOrCollapsed) {
  Eigen::MatrixXd reversed = valve_.annulus_closed.colwise().reverse();
  nlohmann::json points = nlohmann::json::array();
  for (Eigen::Index k = 0; k < reversed.rows(); ++k)
    points.push_back({reversed(k, 0), reversed(k, 1), reversed(k, 2)});
  writeText(dir_ / "annulus_closed.json", nlohmann::json{{"points", points}}.dump());
  expectError("annulus_closed\\.json", "points: the closed annulus runs the other way round");
  points = nlohmann::json::array();
  for (Eigen::Index k = 0; k < reversed.rows(); ++k) points.push_back({1.0, 2.0, 3.0});
  writeText(dir_ / "annulus_closed.json", nlohmann::json{{"points", points}}.dump());
  expectError("annulus_closed\\.json", "points: the closed annulus is 0 mm around");
}

// A closed-annulus point at 1e308 was reported twice: as far from the valve, and as a ring
// "inf mm around" (its length overflowed). The far point is the problem; the ring's length and
// shape are not measured through it.
TEST_F(ValidateCommand, ReportsAClosedAnnulusPointFarFromTheValveOnce) {
  nlohmann::json points = nlohmann::json::array();
  for (Eigen::Index k = 0; k < valve_.annulus_closed.rows(); ++k) {
    const Eigen::RowVector3d p = valve_.annulus_closed.row(k);
    points.push_back({k == 3 ? 1e308 : p.x(), p.y(), p.z()});
  }
  writeText(dir_ / "annulus_closed.json", nlohmann::json{{"points", points}}.dump());
  expectError("annulus_closed\\.json",
              "points\\[3\\]: \\(1e\\+308, .* lies 1e\\+308 mm from the valve");
  const testing::CommandResult r = validate();
  EXPECT_NE(r.err.find("1 problem(s)"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("around"), std::string::npos) << r.err;
  // In a .csv, by its line (a header, then point k on line k + 2).
  std::string csv = "x,y,z\n";
  for (const auto& p : points) csv += p[0].dump() + "," + p[1].dump() + "," + p[2].dump() + "\n";
  writeText(dir_ / "annulus_closed.csv", csv);
  editCaseJson([](nlohmann::json& j) { j["annulus"]["closed"] = "annulus_closed.csv"; });
  expectError("annulus_closed\\.csv", "line 5: \\(1e\\+308, .* lies 1e\\+308 mm from the valve");
}

// From a bad-input sweep: a closed annulus listed from another start (a shifted list, or half
// a turn: RAS points read as LPS) or with a repeated point passed every check; the shifted or
// turned one pulled the ring across the orifice, the repeated one diverged (exit 3).
TEST_F(ValidateCommand, ReportsAClosedAnnulusShiftedTurnedOrWithARepeatedPoint) {
  const Eigen::MatrixXd& closed = valve_.annulus_closed;
  const Eigen::Index n = closed.rows();
  auto writeClosed = [&](const std::function<Eigen::RowVector3d(Eigen::Index)>& point) {
    nlohmann::json points = nlohmann::json::array();
    for (Eigen::Index k = 0; k < n; ++k) {
      const Eigen::RowVector3d p = point(k);
      points.push_back({p(0), p(1), p(2)});
    }
    writeText(dir_ / "annulus_closed.json", nlohmann::json{{"points", points}}.dump());
  };
  writeClosed([&](Eigen::Index k) { return closed.row((k + n - 2) % n); });
  expectError("annulus_closed\\.json",
              "points: the closed annulus fits the ring best shifted by 2 of 8");
  const Eigen::RowVector3d centre = closed.colwise().mean();
  writeClosed([&](Eigen::Index k) {
    Eigen::RowVector3d p = closed.row(k) - centre;
    return Eigen::RowVector3d(centre(0) - p(0), centre(1) - p(1), centre(2) + p(2));
  });
  expectError("annulus_closed\\.json", "shifted by 4 of 8 places .*half a turn");
  writeClosed([&](Eigen::Index k) { return closed.row(k == 3 ? 2 : k); });
  expectError("annulus_closed\\.json", "points\\[2\\]: the side to points\\[3\\] is 0 mm long");
  // Two points swapped: the ring pulled through itself diverged at step 62 (exit 3).
  writeClosed([&](Eigen::Index k) { return closed.row(k == 3 ? 4 : k == 4 ? 3 : k); });
  expectError("annulus_closed\\.json",
              "points\\[3\\]: the closed annulus crosses itself: its side points\\[2\\] to "
              "points\\[3\\] crosses the side points\\[4\\] to points\\[5\\]");
  // The same from a .csv curve: its points named by their lines.
  std::string csv;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::RowVector3d p = closed.row(k == 3 ? 4 : k == 4 ? 3 : k);
    csv += std::to_string(p(0)) + "," + std::to_string(p(1)) + "," + std::to_string(p(2)) + "\n";
  }
  writeText(dir_ / "closed.csv", csv);
  editCaseJson([](nlohmann::json& j) { j["annulus"]["closed"] = "closed.csv"; });
  expectError("closed\\.csv",
              "line 4: the closed annulus crosses itself: its side line 3 to line 4 crosses the "
              "side line 5 to line 6");
  editCaseJson([](nlohmann::json& j) { j["annulus"]["closed"] = "annulus_closed.json"; });
  // Drawn in to 0.4 of its size about its centre (0.35 diverged on the parametric valve).
  writeClosed([&](Eigen::Index k) -> Eigen::RowVector3d {
    const Eigen::RowVector3d p = closed.row(k) - centre;
    return centre + Eigen::RowVector3d(0.4 * p(0), 0.4 * p(1), p(2));
  });
  expectError("annulus_closed\\.json",
              "points: the closed annulus is .* \\(accepted: 0.5 to 4 times\\)");
  // The whole annulus moved toward the apex, turned by 20 degrees about its axis and shrunk by
  // a tenth is no shift: a small rotation between the phases looks like a shift of a place
  // or two.
  const double turn = 20.0 * M_PI / 180.0;
  writeClosed([&](Eigen::Index k) -> Eigen::RowVector3d {
    const Eigen::RowVector3d p = closed.row(k) - centre;
    return centre + Eigen::RowVector3d(0.9 * (std::cos(turn) * p(0) - std::sin(turn) * p(1)),
                                       0.9 * (std::sin(turn) * p(0) + std::cos(turn) * p(1)),
                                       p(2) - 3.0);
  });
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.err.find("annulus_closed.json: points"), std::string::npos) << r.err;
}

// A hole in the leaflet surface (a triangle missing) is simulated as a free edge: every command
// that reads the case warns of it, once, as import-mesh did (validate took it silently); the
// run goes on.
TEST(CaseMeshHoles, AreWarnedOfByEveryCommandThatReadsTheCase) {
  TempDir dir;
  Diagnostics diagnostics;
  std::optional<ValveCase> c =
      loadCase(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal", diagnostics);
  ASSERT_TRUE(c);
  writeCase(dir / "whole", *c);
  // A triangle none of whose vertices lies on the boundary.
  std::vector<bool> on_boundary(c->mesh.V.rows(), false);
  for (const std::vector<int>& loop : boundaryLoops(c->mesh.F))
    for (int v : loop) on_boundary[v] = true;
  Eigen::Index interior = -1;
  for (Eigen::Index f = 0; f < c->mesh.F.rows() && interior < 0; ++f)
    if (!on_boundary[c->mesh.F(f, 0)] && !on_boundary[c->mesh.F(f, 1)] &&
        !on_boundary[c->mesh.F(f, 2)])
      interior = f;
  ASSERT_GE(interior, 0);
  Eigen::MatrixXi F(c->mesh.F.rows() - 1, 3);
  F << c->mesh.F.topRows(interior), c->mesh.F.bottomRows(c->mesh.F.rows() - interior - 1);
  c->mesh.F = F;
  writeCase(dir / "holed", *c);
  const std::string warning =
      "the valve mesh has 1 boundary loop besides the annulus ring and "
      "the free edge: holes in the leaflet surface";
  const std::string holed = testing::quoted(dir / "holed");
  for (const std::string& command :
       {"validate " + holed, "heuristic " + holed + " --out " + testing::quoted(dir / "h.json")}) {
    const auto r = runChordfit(command);
    EXPECT_EQ(r.exit_code, 0) << command << ": " << r.err;
    EXPECT_NE(r.err.find("warning: case " + (dir / "holed").string() + ": " + warning),
              std::string::npos)
        << command << ": " << r.err;
  }
  const auto whole = runChordfit("validate " + testing::quoted(dir / "whole"));
  EXPECT_EQ(whole.exit_code, 0) << whole.err;
  EXPECT_EQ(whole.err.find("boundary loop"), std::string::npos) << whole.err;
}

// Leaflet names make the cord groups and the tracings' leaflets; a leaflet needs vertices.
TEST_F(ValidateCommand, ReportsBlankOrRepeatedLeafletNamesAndALeafletWithoutVertices) {
  editCaseJson([](nlohmann::json& j) { j["leaflets"]["names"] = {"anterior", "anterior"}; });
  expectError("case\\.json",
              "leaflets\\.names\\[1\\]: \"anterior\" repeats leaflets\\.names\\[0\\]");
  editCaseJson([](nlohmann::json& j) { j["leaflets"]["names"] = {"anterior", " "}; });
  expectError("case\\.json", "leaflets\\.names\\[1\\]: a leaflet name must not be blank");
  editCaseJson([](nlohmann::json& j) {
    j["leaflets"]["names"] = {"anterior", "posterior", "septal"};
  });
  expectError("leaflets\\.json", "labels: no vertex is labelled 2 \\(septal\\)");
}

// A leaflet renamed or dropped in case.json shows up in the files that use the names (labels,
// tracings): their errors say which names case.json gives, so the user looks there too.
TEST_F(ValidateCommand, AnUnknownLeafletLabelOrNameIsReportedWithTheNamesCaseJsonGives) {
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "leaflet": "posterior", "points": [[1, 0, -2], [2, 0, -3]]},
                             {"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "leaflet": 2, "points": [[1, 0, -2], [2, 0, -3]]}]})");
  expectError("tracings\\.json",
              "tracings\\[1\\]\\.leaflet: leaflet 2 does not exist: leaflets run from 0 to 1, one "
              "per leaflet name in case\\.json \\(leaflets\\.names or its default: \"anterior\", "
              "\"posterior\"\\)");
  editCaseJson([](nlohmann::json& j) { j["leaflets"]["names"] = {"anterior"}; });
  expectError("leaflets\\.json",
              "labels\\[2\\]: label 1 is not a leaflet: labels run from 0 to 0, one per leaflet "
              "name in case\\.json \\(leaflets\\.names or its default: \"anterior\"\\)");
  expectError("tracings\\.json",
              "tracings\\[0\\]\\.leaflet: \"posterior\" is not a leaflet name of this case: "
              "case\\.json names \"anterior\" \\(leaflets\\.names or its default\\)");
}

// A cord given twice pulls twice as hard, and two tips in one place give every cord one origin.
TEST_F(ValidateCommand, ReportsARepeatedCordAndTwoTipsInOnePlace) {
  CordSet set = cordsFromOneTip(1);
  set.tips.push_back({"posteromedial", Eigen::Vector3d(0, -5, -20), std::nullopt});
  const Cord cord = set.cords[0];
  Cord other = cord;
  other.tip = 1;  // the same insertion from the other tip: a cord of its own
  set.cords = {cord, other, cord};
  useCords(set);
  expectError("cords\\.json",
              "cords\\[2\\]: repeats cords\\[0\\] \\(the same tip and insertion\\)");
  set.cords = {cord, other};
  set.tips[1].position = Eigen::Vector3d(0, 5.5, -20);
  writeCordSet(dir_ / "cords.json", set);
  expectError("cords\\.json", "tips\\[1\\]\\.position: less than 1 mm from tips\\[0\\]\\.position");
}

// Tips are found by name (edit-cords --move-tip) and name the cord groups: two tips of one name
// validated, and --move-tip moved the second without a word.
TEST_F(ValidateCommand, ReportsATipNameGivenTwiceInACordSetOrInPmTips) {
  writeText(dir_ / "cords.json", R"({"format": "chordfit-cordset", "version": 1,
      "tips": [{"name": "anterolateral", "position": [0, 5, -20]},
               {"name": "anterolateral", "position": [0, -5, -20]}],
      "cords": [{"tip": 0, "vertex": 9, "rest_length_mm": 18.0},
                {"tip": 1, "vertex": 12, "rest_length_mm": 18.0}]})");
  editCaseJson([](nlohmann::json& j) { j["cords"] = "cords.json"; });
  expectError("cords\\.json",
              "tips\\[1\\]\\.name: \"anterolateral\" repeats tips\\[0\\]\\.name: each tip "
              "needs a name of its own");
  writeText(dir_ / "pm_tips.json", R"({"tips": [{"name": "pm", "position": [0, 5, -20]},
                                                {"name": "al", "position": [0, -5, -20]},
                                                {"name": "pm", "position": [5, 0, -20]}]})");
  editCaseJson([](nlohmann::json& j) {
    j.erase("cords");
    j["pm_tips"] = "pm_tips.json";
  });
  expectError("pm_tips\\.json", "tips\\[2\\]\\.name: \"pm\" repeats tips\\[0\\]\\.name");
  // An unnamed tip is "tip<index>": a named one may not take that name from it.
  writeText(dir_ / "pm_tips.json", R"({"tips": [{"name": "tip1", "position": [0, 5, -20]},
                                                {"position": [0, -5, -20]}]})");
  expectError("pm_tips\\.json",
              "tips\\[1\\]: unnamed, it is called \"tip1\", which tips\\[0\\]\\.name gives");
}

// pm_tips beside cords was used only by `chordfit heuristic`; simulate and fit close the cords
// on the cord set's own tips. validate says so, and an empty tips list is an error (it read as
// no tips).
TEST_F(ValidateCommand, NotesWhoUsesPmTipsBesideCordsAndRefusesAnEmptyTipsList) {
  CordSet set = cordsFromOneTip(1);
  set.tips.push_back({"posteromedial", Eigen::Vector3d(0, -5, -20), std::nullopt});
  useCords(set);
  writeText(dir_ / "pm_tips.json", R"({"tips": [{"name": "al", "position": [0, 4, -20]},
                                                {"name": "pm", "position": [0, -4, -20]}]})");
  testing::CommandResult r = validate();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("note:"), std::string::npos) << "cords alone: " << r.err;
  editCaseJson([](nlohmann::json& j) { j["pm_tips"] = "pm_tips.json"; });
  r = validate();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: case.json: pm_tips and cords are both given: simulate, fit, "
                       "sweep-cord, compare and edit-cords take the cords with the cord set's own "
                       "tips and do not read pm_tips; only `chordfit heuristic` uses it"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("valid\n"), std::string::npos) << r.out;
  // Another count than the cord set's: the heuristic cannot pair them, and refuses.
  writeText(dir_ / "pm_tips.json", R"({"tips": [{"name": "al", "position": [0, 4, -20]}]})");
  r = validate();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1 PM tip for the cord set's 2 tips"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("`chordfit heuristic` refuses"), std::string::npos) << r.err;

  writeText(dir_ / "pm_tips.json", R"({"tips": []})");
  expectError("pm_tips\\.json",
              "tips: no tips: give at least one, or leave pm_tips out of "
              "case\\.json");
}

// A piece of the mesh with no ring vertex hangs from nothing: a stray copy of the leaflets
// drifted to the step cap and exit 0.
TEST_F(ValidateCommand, ReportsAPieceOfTheMeshThatNoRingVertexIsOn) {
  const Eigen::Index n = valve_.mesh.V.rows();
  valve_.mesh.V.conservativeResize(n + 3, Eigen::NoChange);
  valve_.mesh.V.bottomRows(3) << 0, 0, -2, 1, 0, -2, 0, 1, -2;
  valve_.mesh.F.conservativeResize(valve_.mesh.F.rows() + 1, Eigen::NoChange);
  valve_.mesh.F.bottomRows(1) << n, n + 1, n + 2;
  valve_.mesh.leaflet.conservativeResize(n + 3);
  valve_.mesh.leaflet.tail(3).setZero();
  writeCase(dir_.path(), valve_);
  expectError("annulus_ring\\.json", "belongs to a piece of the mesh that no ring vertex is on");
}

// A cord inserted on the annulus ring pulls on nothing the closure moves, or, through a leaflet
// vertex of tiny weight, throws that vertex away: a point with weight 1e-12 off the ring made the
// closure diverge at step 1 ("reduce dt_ms").
TEST_F(ValidateCommand, ReportsACordInsertedOnTheAnnulusRing) {
  const Eigen::VectorXi& ring = valve_.mesh.annulus;
  auto onRing = [&ring](int v) { return (ring.array() == v).any(); };
  CordPoint point;  // a triangle with two ring vertices, nearly all the weight on them
  bool found = false;
  for (Eigen::Index f = 0; f < valve_.mesh.F.rows() && !found; ++f) {
    std::array<int, 3> v{valve_.mesh.F(f, 0), valve_.mesh.F(f, 1), valve_.mesh.F(f, 2)};
    std::stable_partition(v.begin(), v.end(), onRing);
    if (onRing(v[0]) && onRing(v[1]) && !onRing(v[2])) {
      point.vertices = v;
      point.weights = Eigen::Vector3d(0.6, 0.4 - 1e-12, 1e-12);
      found = true;
    }
  }
  ASSERT_TRUE(found) << "no triangle with two ring vertices";
  CordSet set;
  set.tips.push_back({"anterolateral", Eigen::Vector3d(0, 5, -20), std::nullopt});
  Cord cord;
  cord.vertex = point.vertices[0];
  cord.point = point;
  cord.rest_length = cord.seed_rest_length = 20.0;
  Cord on_vertex = cord;
  on_vertex.point.reset();
  on_vertex.vertex = ring(1);
  set.cords = {cord, on_vertex};
  writeCordSet(dir_ / "cords.json", set);
  editCaseJson([](nlohmann::json& j) { j["cords"] = "cords.json"; });
  expectError("cords\\.json",
              "cords\\[0\\]\\.point: the insertion lies on the annulus ring \\(100 % of its weight "
              "on ring vertices " +
                  std::to_string(point.vertices[0]) + ", " + std::to_string(point.vertices[1]));
  expectError("cords\\.json", "cords\\[1\\]\\.vertex: the insertion lies on the annulus ring");
  // The same set given to simulate --cords on the case without it: refused before any closure
  // (by the --cords reader, not by the case's loading).
  editCaseJson([](nlohmann::json& j) { j.erase("cords"); });
  ASSERT_EQ(validate().exit_code, 0) << "the case without the cord set is fine";
  const auto r =
      runChordfit("simulate " + testing::quoted(dir_.path()) + " --cords " +
                  testing::quoted(dir_ / "cords.json") + " --out " + testing::quoted(dir_ / "sim"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("a cord must pull on the leaflet"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "sim"));
}

// A case.json that is a loop of links, or a directory the user may not search, is not "not
// found".
TEST_F(ValidateCommand, SaysWhyACaseFileThatIsALoopOfLinksCannotBeRead) {
  std::filesystem::remove(dir_ / "case.json");
  std::filesystem::create_symlink("other.json", dir_ / "case.json");
  std::filesystem::create_symlink("case.json", dir_ / "other.json");
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("case.json: cannot be read (Too many levels of symbolic links)"),
            std::string::npos)
      << r.err;
}

// A file the user may not read says why, as the case directory does ("cannot be read" alone
// left permissions, a lock or a broken disk to guess). Root reads anything: as root the
// command runs as nobody (setpriv), or the test is skipped.
TEST_F(ValidateCommand, SaysWhyAFileInTheCaseCannotBeRead) {
  namespace fs = std::filesystem;
  const bool root = ::geteuid() == 0;
  const fs::path setpriv = "/usr/bin/setpriv";
  if (root && !fs::exists(setpriv)) GTEST_SKIP() << "root reads a file of mode 000";
  // The case stays readable to others (nobody reaches it), but for its mesh.
  fs::permissions(dir_.path(), fs::perms::others_read | fs::perms::others_exec,
                  fs::perm_options::add);
  for (const auto& entry : fs::directory_iterator(dir_.path()))
    fs::permissions(entry.path(), fs::perms::others_read, fs::perm_options::add);
  fs::permissions(dir_ / "open.ply", fs::perms::none);
  const std::string validate_args = "validate '" + dir_.path().string() + "'";
  const testing::CommandResult r =
      root ? testing::runProgram(setpriv, "--reuid=65534 --regid=65534 --clear-groups '" +
                                              std::string(CHORDFIT_EXE) + "' " + validate_args)
           : runChordfit(validate_args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("open.ply: cannot be read (Permission denied)"), std::string::npos) << r.err;
}

// A tracing's curve file is relative to the tracings file naming it, as import-mesh --tracings
// reads it (it was relative to the case directory, so the same tracings file worked in one
// command and failed in the other).
TEST_F(ValidateCommand, ReadsATracingsCurveFileBesideTheTracingsFile) {
  std::filesystem::create_directories(dir_ / "echo");
  writeText(dir_ / "echo" / "t.csv", "x,y,z\n8,0,-4\n7,0,-6\n");
  writeText(dir_ / "echo" / "tracings.json",
            R"({"tracings": [{"plane": {"origin": [0, 0, 0], "normal": [0, 1, 0]},
                              "file": "t.csv"}]})");
  editCaseJson([](nlohmann::json& j) { j["tracings"] = "echo/tracings.json"; });
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::filesystem::rename(dir_ / "echo" / "t.csv", dir_ / "t.csv");
  expectError("echo/tracings\\.json",
              "tracings\\[0\\]\\.file: \"t\\.csv\": file not found in .*echo");
}

// One bad value looked at for several fields is one problem, reported once (a number where a
// tracing belongs read "expected an object, got number" four times, "4 problem(s)").
TEST_F(ValidateCommand, ReportsOneBadValueOnce) {
  useTracings(R"({"tracings": [5]})");
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(testing::occurrences(r.err, "tracings[0]: expected an object, got number"), 1u)
      << r.err;
  editCaseJson([](nlohmann::json& j) { j["leaflets"] = "x"; });
  const testing::CommandResult leaflets = validate();
  EXPECT_EQ(testing::occurrences(leaflets.err, "leaflets: expected an object, got string"), 1u)
      << leaflets.err;
}

// A UTF-8 byte-order mark, as spreadsheet exports write it: skipped in a CSV curve; named in a
// mesh file (it read as "first line is not 'ply'", the mark invisible).
TEST_F(ValidateCommand, SkipsAByteOrderMarkInACsvCurveAndNamesItInAMesh) {
  std::string csv = std::string("\xEF\xBB\xBF") + "x,y,z\n";
  for (Eigen::Index k = 0; k < valve_.annulus_closed.rows(); ++k) {
    const Eigen::RowVector3d p = valve_.annulus_closed.row(k);
    csv += std::to_string(p(0)) + "," + std::to_string(p(1)) + "," + std::to_string(p(2)) + "\n";
  }
  writeText(dir_ / "annulus_closed.csv", csv);
  editCaseJson([](nlohmann::json& j) { j["annulus"]["closed"] = "annulus_closed.csv"; });
  testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const std::string mesh = testing::readText(dir_ / "open.ply");
  writeText(dir_ / "open.ply", "\xEF\xBB\xBF" + mesh);
  expectError("open\\.ply", "starts with a UTF-8 byte-order mark");
}

// Binary garbage in a curve file was echoed as it was (NUL bytes, escape sequences, broken
// UTF-8 on the terminal): non-printable bytes are shown as \xNN, a long value cut with "…".
TEST_F(ValidateCommand, QuotesBinaryBytesOfACurveFileEscaped) {
  const std::string garbage("\xac\xae\0\x1b[31m", 8);  // 8 characters shown
  writeText(dir_ / "t.csv", "x,y,z\n1,0,-2\n" + garbage + std::string(60, 'A') + ",0,-2\n");
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "file": "t.csv"}]})");
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: t.csv: line 3: x is not a finite decimal number: "
                       "\"\\xac\\xae\\x00\\x1b[31m" +
                       std::string(32, 'A') + "…\"\n"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find('\0'), std::string::npos);
  EXPECT_EQ(r.err.find('\x1b'), std::string::npos);
}

// One tracing, one cord, one tip: the summary read "1 polylines", "1 cords on 1 tips".
TEST_F(ValidateCommand, SummaryCountsOneOfAThingInTheSingular) {
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                                "points": [[1, 0, -2], [2, 0, -2]]}]})");
  useCords(cordsFromOneTip(1));
  const testing::CommandResult r = validate();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("tracings:  1 polyline, 2 points\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("cords:     1 cord on 1 tip\n"), std::string::npos) << r.out;
}

// The case's name titles SVG figures (no control characters allowed) and Markdown tables.
TEST_F(ValidateCommand, ReportsAControlCharacterInTheCaseName) {
  editCaseJson([](nlohmann::json& j) { j["name"] = "two\nlines"; });
  expectError("case\\.json", "name: contains a control character");
}

// A leaflet's name is part of its cord groups' names, which edit-cords --group NAME=S takes: a
// newline broke the summary and the groups, a '/' made groups edit-cords could not tell apart
// ("a/b/anterolateral"). Both passed.
TEST_F(ValidateCommand, ReportsALeafletNameWithAControlCharacterOrASlash) {
  editCaseJson([](nlohmann::json& j) { j["leaflets"]["names"] = {"anterior", "a\nb"}; });
  expectError(
      "case\\.json",
      "leaflets\\.names\\[1\\]: \"a\\\\x0ab\" contains a control character \\(\\\\x0a\\): give "
      "a name of printable characters");
  editCaseJson([](nlohmann::json& j) { j["leaflets"]["names"] = {"a/b", "c"}; });
  expectError("case\\.json",
              "leaflets\\.names\\[0\\]: \"a/b\" contains '/', which joins a cord "
              "group's leaflet and tip");
  // The characters edit-cords parses apart stay allowed: ',' and '=' (NAME=S is split at the
  // last '=').
  editCaseJson([](nlohmann::json& j) { j["leaflets"]["names"] = {"anterior, AML", "b=c"}; });
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST_F(ValidateCommand, ReportsATracingWithBothPointsAndAFile) {
  writeText(dir_ / "tracing.csv", "1,0,-2\n2,0,-2\n");
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "leaflet": "posterior", "points": [[1, 0, -2], [2, 0, -2]],
                              "file": "tracing.csv"}]})");
  expectError("tracings\\.json", "tracings\\[0\\]: give \"points\" or \"file\", not both");
}

// A case's simulation block cannot choose the phase: every command closes (simulate --phase
// open opens after), so an accepted "phase" was ignored.
TEST_F(ValidateCommand, ReportsAPhaseInTheSimulationBlock) {
  editCaseJson([](nlohmann::json& j) { j["simulation"] = {{"phase", "open"}}; });
  expectError(".*case\\.json", "simulation\\.phase: a case's settings cannot choose the phase");
}

TEST_F(ValidateCommand, ReportsATracingWithFewerThanTwoPoints) {
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "leaflet": "posterior", "points": [[1, 0, -2]]}]})");
  expectError("tracings\\.json", "tracings\\[0\\]\\.points: a tracing needs at least 2 points");
  // From a curve file, the file is named as the "no length" message names it.
  writeText(dir_ / "one.csv", "x,y,z\n1,0,-2\n");
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "file": "one.csv"}]})");
  expectError("tracings\\.json",
              "tracings\\[0\\]\\.file: one\\.csv: a tracing needs at least 2 points, got 1");
}

// Two or more points all in one place used to pass as a tracing of no length, inline or in a
// curve file.
TEST_F(ValidateCommand, ReportsATracingWithoutLengthNamingItsFile) {
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "points": [[1, 0, -2], [1, 0, -2], [1, 0, -2]]}]})");
  expectError("tracings\\.json",
              "tracings\\[0\\]\\.points: the tracing has no length: its 3 points all lie at "
              "\\(1, 0, -2\\) \\(within 0\\.001 mm of the first\\); a tracing needs at least 2 "
              "distinct points\n");
  writeText(dir_ / "tracing_01.csv", "x,y,z\n1,0,-2\n1.0000001,0,-2\n");
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "file": "tracing_01.csv"}]})");
  expectError("tracings\\.json",
              "tracings\\[0\\]\\.file: tracing_01\\.csv: the tracing has no length: its 2 points");
}

// Repeated points inside a tracing of some length stay accepted: each is measured as a point.
TEST_F(ValidateCommand, AcceptsATracingThatRepeatsAPoint) {
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "points": [[1, 0, -2], [1, 0, -2], [2, 0, -2], [2, 0, -2]]}]})");
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
}

// Finite but absurd coordinates pass the format checks and then break the computation (a
// figure's axis looping, a resampling allocating without bound): case_extent.h.
TEST_F(ValidateCommand, ReportsATracingPointFarFromTheValve) {
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "leaflet": "posterior", "points": [[1e10, 0, -2], [1, 0, -2]]}]})");
  expectError("tracings\\.json", "tracings\\[0\\]\\.points\\[0\\]: .* from the valve mesh");
  // From a curve file, the point is named where it stands: its file and line (it was named as
  // "tracings[0].points[2]" of the tracings file, which has no points).
  writeText(dir_ / "t.csv", "x,y,z\n1,0,-2\n2,0,-2\n1e10,0,-2\n");
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "leaflet": "posterior", "file": "t.csv"}]})");
  expectError("t\\.csv", "line 4: \\(1e\\+10, 0, -2\\) lies .* from the valve mesh");
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.err.find("points["), std::string::npos) << r.err;
}

TEST_F(ValidateCommand, ReportsATracingOffItsPlane) {
  // Near the valve, but 5 mm off the plane y = 0 it claims to be drawn on.
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "points": [[1, 0, -2], [2, 5, -2], [3, 5, -2]]}]})");
  expectError("tracings\\.json",
              "tracings\\[0\\]\\.points: 2 of 3 points lie off the tracing's plane \\(first: "
              "point 1; farthest 5 mm");
}

// Points in RAS read as LPS (x and y negated): off the plane y = 3, on it once negated back.
TEST_F(ValidateCommand, ATracingOffItsPlaneThatRasWouldPutOnItSaysSo) {
  useTracings(R"({"tracings": [{"plane": {"origin": [0,3,0], "normal": [0,1,0]},
                              "points": [[1, -3, -2], [2, -3, -2]]}]})");
  expectError("tracings\\.json",
              "2 of 2 points lie off the tracing's plane .*with x and y negated they lie on it: "
              "are they in RAS\\?");
}

// In a curve file the advice is the file format's own way of saying its system: an .fcsv
// without a CoordinateSystem line is read as RAS, so LPS numbers in it need that line; a
// plain .csv is read as LPS and names r,a,s columns for RAS.
TEST_F(ValidateCommand, ATracingFileInTheOtherSystemGetsItsFormatsAdvice) {
  testing::writeText(dir_ / "lps.fcsv", "# columns = id,x,y,z\n1,1,3,-2\n2,2,3,-2\n");
  useTracings(R"({"tracings": [{"plane": {"origin": [0,3,0], "normal": [0,1,0]},
                              "file": "lps.fcsv"}]})");
  expectError("tracings\\.json",
              "with x and y negated they lie on it: the file was read as RAS; are they in LPS\\? "
              "\\(say \"# CoordinateSystem = LPS\" in the file's header \\(an \\.fcsv without "
              "that line is read as RAS\\)\\)");
  testing::writeText(dir_ / "ras.csv", "1,-3,-2\n2,-3,-2\n");
  useTracings(R"({"tracings": [{"plane": {"origin": [0,3,0], "normal": [0,1,0]},
                              "file": "ras.csv"}]})");
  expectError("tracings\\.json", "are they in RAS\\? \\(name the columns r,a,s in a header row\\)");
}

// [1e308, 1, 0] has finite components but an infinite length: it used to normalise to a zero
// vector, on whose "plane" every point lies, and validate.
TEST_F(ValidateCommand, ReportsATracingNormalWhoseLengthOverflows) {
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [1e308, 1, 0]},
                              "points": [[1, 0, -2], [2, 5, -2], [3, 5, -2]]}]})");
  expectError("tracings\\.json",
              "tracings\\[0\\]\\.plane\\.normal: plane normal is too long to normalise");
}

// "tracings": "" used to read the case directory itself as JSON ("error: : line 1, column
// 1: malformed JSON"); a directory or a device named by a file field is refused at the field.
TEST_F(ValidateCommand, ReportsASideFileFieldThatIsEmptyOrNamesADirectory) {
  std::filesystem::create_directory(dir_ / "sub");
  editCaseJson([](nlohmann::json& j) { j["tracings"] = ""; });
  expectError("case\\.json", "tracings: no file given \\(an empty file name\\)");
  editCaseJson([](nlohmann::json& j) { j["tracings"] = "sub"; });
  expectError("case\\.json", "tracings: \"sub\" is a directory");
  editCaseJson([](nlohmann::json& j) {
    j.erase("tracings");
    j["pm_tips"] = "/dev/null";
  });
  expectError("case\\.json", "pm_tips: \"/dev/null\" is not a regular file");
}

TEST_F(ValidateCommand, ReportsATracingFileFieldThatIsEmptyOrNamesADirectory) {
  std::filesystem::create_directory(dir_ / "sub");
  editCaseJson([](nlohmann::json& j) { j["tracings"] = "tracings.json"; });
  for (const auto& [file, message] :
       {std::pair<std::string, std::string>{"", "no file given"},
        std::pair<std::string, std::string>{"sub", "\"sub\" is a directory"}}) {
    writeText(dir_ / "tracings.json",
              R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                                "file": ")" +
                  file + R"("}]})");
    expectError("tracings\\.json", "tracings\\[0\\]\\.file: " + message);
  }
}

// "tracing" (for "tracings") used to validate as a case without tracings, while the
// simulation block already refused unknown keys.
TEST_F(ValidateCommand, ReportsAnUnknownCaseKeySuggestingTheNearestKnownOne) {
  writeText(dir_ / "tracings.json",
            R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "points": [[1, 0, -2], [2, 0, -2]]}]})");
  editCaseJson([](nlohmann::json& j) { j["tracing"] = "tracings.json"; });
  expectError("case\\.json", "tracing: unknown key; did you mean \"tracings\"\\?");
  editCaseJson([](nlohmann::json& j) {
    j.erase("tracing");
    j["annulus"]["closd"] = j["annulus"]["closed"];
  });
  expectError("case\\.json", "annulus\\.closd: unknown key; did you mean \"closed\"\\?");
  editCaseJson([](nlohmann::json& j) {
    j["annulus"].erase("closd");
    j["comment"] = "by hand";
  });
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: case.json: comment: unknown key\n"), std::string::npos) << r.err;
}

TEST_F(ValidateCommand, ReportsAnUnknownCordKeySuggestingTheNearestKnownOne) {
  useCords(cordsFromOneTip(1),
           [](nlohmann::json& cords) { cords["cords"][0]["compliance_mm_per_n"] = 0.05; });
  expectError("cords\\.json",
              "cords\\[0\\]\\.compliance_mm_per_n: unknown key; did you mean "
              "\"compliance_mm_per_N\"\\?");
}

// A key given twice used to keep its last value without a word: two "rest_length_mm" of one
// cord read the second, two "mesh" keys the second mesh.
TEST_F(ValidateCommand, ReportsADuplicateKeyNamingTheFileAndItsPath) {
  writeText(dir_ / "cords.json", R"({"format": "chordfit-cordset", "version": 1,
      "tips": [{"name": "anterolateral", "position": [0, 5, -20]}],
      "cords": [{"tip": 0, "vertex": 9, "rest_length_mm": 18.0, "rest_length_mm": 1e-300}]})");
  editCaseJson([](nlohmann::json& j) { j["cords"] = "cords.json"; });
  expectError("cords\\.json",
              "cords\\[0\\]\\.rest_length_mm: duplicate key: given more than once in this "
              "object, and only one of its values would be read: keep one");
  std::string text = testing::readText(dir_ / "case.json");
  text.replace(text.find('{'), 1, R"({"mesh": "elsewhere.ply",)");
  writeText(dir_ / "case.json", text);
  expectError("case\\.json", "mesh: duplicate key");
}

// A misspelt "closed_position" used to leave the tip static without a word, in pm_tips.json
// as in a cord set's tips.
TEST_F(ValidateCommand, ReportsAnUnknownTipKeySuggestingTheNearestKnownOne) {
  writeText(dir_ / "pm_tips.json",
            R"({"tips": [{"name": "anterolateral", "position": [0, 5, -20],
                          "closed_positon": [0, 5, -19]}]})");
  editCaseJson([](nlohmann::json& j) { j["pm_tips"] = "pm_tips.json"; });
  expectError("pm_tips\\.json",
              "tips\\[0\\]\\.closed_positon: unknown key; did you mean \"closed_position\"\\?");

  editCaseJson([](nlohmann::json& j) { j.erase("pm_tips"); });
  CordSet set;
  set.tips.push_back({"anterolateral", Eigen::Vector3d(0, 5, -20), Eigen::Vector3d(0, 5, -19)});
  Cord cord;
  cord.vertex = 9;
  cord.rest_length = cord.seed_rest_length = 20.0;
  set.cords = {cord};
  writeCordSet(dir_ / "cords.json", set);
  nlohmann::json cords = nlohmann::json::parse(testing::readText(dir_ / "cords.json"));
  cords["tips"][0]["label"] = "AL";
  writeText(dir_ / "cords.json", cords.dump());
  editCaseJson([](nlohmann::json& j) { j["cords"] = "cords.json"; });
  expectError("cords\\.json", "tips\\[0\\]\\.label: unknown key\n");
}

// A misspelt "leaflet" used to leave the tracing unlabelled (measured to the whole mesh).
TEST_F(ValidateCommand, ReportsAnUnknownTracingKeySuggestingTheNearestKnownOne) {
  useTracings(R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0]},
                              "leaflett": "posterior", "points": [[1, 0, -2], [2, 0, -2]]}]})");
  expectError("tracings\\.json",
              "tracings\\[0\\]\\.leaflett: unknown key; did you mean \"leaflet\"\\?");
  writeText(dir_ / "tracings.json",
            R"({"tracings": [{"plane": {"origin": [0,0,0], "normal": [0,1,0], "spacing": 1},
                              "points": [[1, 0, -2], [2, 0, -2]]}]})");
  expectError("tracings\\.json", "tracings\\[0\\]\\.plane\\.spacing: unknown key\n");
}

TEST_F(ValidateCommand, ReportsATimeStepTooSmallToUse) {
  editCaseJson([](nlohmann::json& j) { j["simulation"] = {{"dt_ms", 1e-300}}; });
  expectError("[^\\n]*case\\.json", "simulation\\.dt_ms: 1e-300 is below");
}

TEST_F(ValidateCommand, ReportsAMeshThatIsNotInMillimetres) {
  valve_.mesh.V *= 1e6;
  valve_.annulus_closed *= 1e6;
  writeCase(dir_.path(), valve_);
  expectError("open\\.ply", "vertices: the mesh spans .* must be in millimetres");
  valve_.mesh.V *= 1e-9;  // metres
  valve_.annulus_closed *= 1e-9;
  writeCase(dir_.path(), valve_);
  expectError("open\\.ply", "vertices: the mesh spans .* must be in millimetres");
}

// One vertex at y = -1e10 used to give a "degenerate triangle" line for every face (their
// zero-area tolerance scales with the bounding box) and never name the vertex.
TEST_F(ValidateCommand, ReportsAnOutlierVertexByTheSpanNotByEveryTriangle) {
  valve_.mesh.V(3, 1) = -1e10;
  writePly(dir_ / "open.ply", valve_.mesh.V, valve_.mesh.F);
  expectError("open\\.ply",
              "vertices: the mesh spans 1e\\+10 mm .*farthest from the median of the vertices: "
              "vertex 3 at \\([^)]*-1e\\+10[^)]*\\)");
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.err.find("degenerate"), std::string::npos) << r.err;
  EXPECT_EQ(testing::occurrences(r.err, "error: "), 1u) << r.err;
}

TEST_F(ValidateCommand, ReportsAPmTipFarFromTheValve) {
  writeText(dir_ / "pm_tips.json",
            R"({"tips": [{"name": "anterolateral", "position": [0, 5, -1e6]},
                         {"name": "posteromedial", "position": [0, -5, -20]}]})");
  editCaseJson([](nlohmann::json& j) { j["pm_tips"] = "pm_tips.json"; });
  expectError("pm_tips\\.json", "tips\\[0\\]\\.position: .* from the valve mesh");
}

// validate checks the simulator overrides as simulate and fit read them.
TEST_F(ValidateCommand, ReportsAnOutOfRangeSimulationOverride) {
  editCaseJson([](nlohmann::json& j) { j["simulation"] = {{"pressure_mmhg", -100}}; });
  expectError("[^\\n]*case\\.json", "pressure_mmhg");
}

TEST_F(ValidateCommand, ReportsACordOnAMissingVertex) {
  CordSet set = cordsFromOneTip(1);
  set.cords[0].vertex = 9999;
  useCords(set);
  expectError("cords\\.json", "cords\\[0\\]\\.vertex: vertex 9999 does not exist");
}

// 1e308 used to validate and then make the closure diverge (exit 3) without naming the cord.
TEST_F(ValidateCommand, ReportsAnAbsurdCordRestLengthOrComplianceNamingTheCord) {
  const std::pair<const char*, std::string> cases[] = {
      {"rest_length_mm", "cords\\[1\\]\\.rest_length_mm: must be at most 1000 mm .*got 1e\\+308"},
      {"seed_rest_length_mm", "cords\\[1\\]\\.seed_rest_length_mm: must be at most 1000 mm"},
      {"compliance_mm_per_N",
       "cords\\[1\\]\\.compliance_mm_per_N: must be at most 10 mm/N .*got 1e\\+308"}};
  for (const auto& [field, message] : cases) {
    useCords(cordsFromOneTip(2),
             [field = field](nlohmann::json& cords) { cords["cords"][1][field] = 1e308; });
    expectError("cords\\.json", message);
  }
}

// 1e-300 mm (a seed that makes every scale nonsense) and 0.5 mm used to validate: a cord that
// short would pin its insertion to the PM tip.
TEST_F(ValidateCommand, ReportsACordRestLengthBelowOneMillimetreNamingTheCord) {
  const std::pair<const char*, double> cases[] = {
      {"seed_rest_length_mm", 1e-300}, {"rest_length_mm", 0.5}, {"rest_length_mm", -5.0}};
  for (const auto& [field, length] : cases) {
    useCords(cordsFromOneTip(2), [field = field, length = length](nlohmann::json& cords) {
      cords["cords"][1][field] = length;
    });
    std::ostringstream got;
    got << length;
    expectError("cords\\.json",
                std::string("cords\\[1\\]\\.") + field +
                    ": must be at least 1 mm \\(chordae are 10-40 mm long.*\\), got " + got.str() +
                    "\n");
  }
}

// make-case's flail truths model a ruptured cord as ten times its length (~250-300 mm): the
// bound must let the project's own truth/cords.json through.
TEST_F(ValidateCommand, AcceptsARupturedCordTenTimesItsLength) {
  CordSet set;
  set.tips.push_back({"anterolateral", Eigen::Vector3d(0, 5, -20), std::nullopt});
  Cord cord;
  cord.vertex = 9;
  cord.seed_rest_length = 30.0;
  cord.rest_length = 10.0 * cord.seed_rest_length;
  set.cords = {cord};
  writeCordSet(dir_ / "cords.json", set);
  editCaseJson([](nlohmann::json& j) { j["cords"] = "cords.json"; });
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
}

TEST_F(ValidateCommand, ReportsACordOnAMissingTip) {
  writeText(dir_ / "cords.json", R"({"format": "chordfit-cordset", "version": 1,
      "tips": [{"name": "anterolateral", "position": [0, 5, -20]}],
      "cords": [{"tip": 3, "vertex": 9, "kind": "primary", "rest_length_mm": 18.0}]})");
  editCaseJson([](nlohmann::json& j) { j["cords"] = "cords.json"; });
  expectError("cords\\.json", "cords\\[0\\]\\.tip: tip 3 does not exist");
}

TEST_F(ValidateCommand, ReportsALeafletLabelCountThatDoesNotMatchTheVertexCount) {
  writeText(dir_ / "leaflets.json", R"({"labels": [0, 0, 1]})");
  expectError("leaflets\\.json", "labels: 3 leaflet labels for a mesh of 16 vertices");
}

TEST_F(ValidateCommand, ReportsSeveralProblemsInOneRun) {
  writeText(dir_ / "leaflets.json", R"({"labels": [0, 0, 1]})");
  writeText(dir_ / "annulus_closed.json", R"({"points": [[1,0,0],[0,1,0],[0,0,1]]})");
  const testing::CommandResult r = validate();
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: leaflets.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("error: annulus_closed.json"), std::string::npos) << r.err;
}

TEST_F(ValidateCommand, ReportsATissueStiffnessCountThatDoesNotMatchTheVertexCount) {
  writeText(dir_ / "tissue.json", R"({"stiffness": [1, 0.5, 1]})");
  editCaseJson([](nlohmann::json& j) { j["tissue_stiffness"] = "tissue.json"; });
  expectError("tissue\\.json", "stiffness: 3 stiffness factors for a mesh of 16 vertices");
}

TEST_F(ValidateCommand, ReportsANonPositiveTissueStiffness) {
  std::vector<double> factors(16, 1.0);
  factors[4] = 0.0;
  writeText(dir_ / "tissue.json", nlohmann::json{{"stiffness", factors}}.dump());
  editCaseJson([](nlohmann::json& j) { j["tissue_stiffness"] = "tissue.json"; });
  expectError("tissue\\.json",
              "stiffness\\[4\\]: stiffness factor must be in \\(0, 1000\\], got 0");
}

TEST(CaseRoundTrip, WriteThenLoadGivesTheSameCase) {
  TempDir dir;
  ValveCase original = tinyConeCase();
  Tracing t;
  t.points = Eigen::MatrixXd::Random(5, 3);
  t.plane_origin = Eigen::Vector3d(0, 0, 0);
  t.plane_normal = Eigen::Vector3d(0, 1, 0);
  t.leaflet = 1;
  original.tracings.push_back(t);
  original.tips = std::vector<PmTip>{{"anterolateral", Eigen::Vector3d(1, 2, -20), std::nullopt}};
  writeCase(dir.path(), original);
  Diagnostics diagnostics;
  const auto loaded = loadCase(dir.path(), diagnostics);
  ASSERT_TRUE(loaded.has_value()) << diagnostics.problems().front().what;
  EXPECT_EQ(loaded->mesh.V, original.mesh.V);
  EXPECT_EQ(loaded->mesh.F, original.mesh.F);
  EXPECT_EQ(loaded->mesh.leaflet, original.mesh.leaflet);
  EXPECT_EQ(loaded->mesh.annulus, original.mesh.annulus);
  EXPECT_EQ(loaded->annulus_closed, original.annulus_closed);
  ASSERT_EQ(loaded->tracings.size(), 1u);
  EXPECT_EQ(loaded->tracings[0].points, t.points);
  EXPECT_EQ(loaded->tracings[0].leaflet, 1);
  ASSERT_TRUE(loaded->tips.has_value());
  EXPECT_EQ((*loaded->tips)[0].position, Eigen::Vector3d(1, 2, -20));
}

// The tiny cone with every optional part a case can have: tracings with a leaflet, PM tips with
// closed positions, cords with a point insertion, regional tissue.
ValveCase tinyConeCaseWithEverything() {
  ValveCase original = tinyConeCase();
  Tracing t;
  t.points = Eigen::MatrixXd::Random(4, 3);
  t.points.col(1).setZero();
  t.plane_origin = Eigen::Vector3d(0, 0, 0);
  t.plane_normal = Eigen::Vector3d(0, 1, 0);
  t.leaflet = 0;
  original.tracings.push_back(t);
  const PmTip tip{"anterolateral", Eigen::Vector3d(1, 2, -20), Eigen::Vector3d(1, 2, -19)};
  original.tips = std::vector<PmTip>{tip};
  CordSet set;
  set.tips = {tip};
  Cord cord;
  cord.point = CordPoint{{8, 9, 1}, Eigen::Vector3d(0.5, 0.3, 0.2)};
  cord.vertex = 8;
  cord.rest_length = cord.seed_rest_length = 20.0;
  set.cords = {cord};
  original.cords = set;
  original.tissue_stiffness = Eigen::VectorXd::Constant(original.mesh.V.rows(), 0.5);
  return original;
}

// Unknown keys are errors in tips, tracings, cords and their points: every key chordfit writes
// there must be among the known ones when the case is read back.
TEST(CaseRoundTrip, EveryKeyChordfitWritesIsKnownOnReading) {
  TempDir dir;
  const ValveCase original = tinyConeCaseWithEverything();
  writeCase(dir.path(), original);
  const PmTip& tip = (*original.tips)[0];
  const Cord& cord = original.cords->cords[0];
  Diagnostics diagnostics;
  const auto loaded = loadCase(dir.path(), diagnostics);
  ASSERT_TRUE(loaded.has_value()) << diagnostics.problems().front().file << ": "
                                  << diagnostics.problems().front().where << ": "
                                  << diagnostics.problems().front().what;
  EXPECT_EQ((*loaded->tips)[0].closed_position, tip.closed_position);
  EXPECT_EQ(loaded->cords->tips[0].closed_position, tip.closed_position);
  EXPECT_EQ(loaded->cords->cords[0].point->weights, cord.point->weights);
  EXPECT_EQ(loaded->tracings[0].leaflet, 0);
}

// The commands writing a case declare caseFileNames() as their outputs, and their staging
// directory refuses any other file: writeCase must stay within it.
TEST(CaseRoundTrip, WritesNoFileBesidesCaseFileNames) {
  TempDir dir;
  writeCase(dir.path(), tinyConeCaseWithEverything());
  const std::vector<std::string> declared = caseFileNames();
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    ++files;
    const std::string name = entry.path().filename().string();
    EXPECT_NE(std::find(declared.begin(), declared.end(), name), declared.end()) << name;
  }
  EXPECT_EQ(files, static_cast<int>(declared.size())) << "the case has every part";
}

TEST(CaseRoundTrip, RegionalTissueIsWrittenAndReadBack) {
  TempDir dir;
  ValveCase original = tinyConeCase();
  original.tissue_stiffness = Eigen::VectorXd::LinSpaced(original.mesh.V.rows(), 0.05, 1.0);
  writeCase(dir.path(), original);
  Diagnostics diagnostics;
  const auto loaded = loadCase(dir.path(), diagnostics);
  ASSERT_TRUE(loaded.has_value()) << diagnostics.problems().front().what;
  EXPECT_EQ(loaded->tissue_stiffness, original.tissue_stiffness);  // bit for bit
  // A case without regional tissue writes no tissue file and reads back uniform.
  TempDir plain;
  writeCase(plain.path(), tinyConeCase());
  EXPECT_FALSE(std::filesystem::exists(plain / "tissue.json"));
  const auto uniform = loadCase(plain.path(), diagnostics);
  ASSERT_TRUE(uniform.has_value());
  EXPECT_EQ(uniform->tissue_stiffness.size(), 0);
}

}  // namespace
}  // namespace chordfit
