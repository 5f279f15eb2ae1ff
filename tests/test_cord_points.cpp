// Cords inserting between vertices (core/cordset.h CordPoint): the file format and its errors,
// the simulator's point constraint against the vertex one, and the cohort's point attachments,
// which put a cord at the same anatomical place on meshes of any resolution.
#include <algorithm>
#include <filesystem>
#include <regex>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/case_io.h"
#include "core/closure_model.h"
#include "core/cord_attachments.h"
#include "core/cord_insertion.h"
#include "core/cordset_io.h"
#include "core/heuristic.h"
#include "core/parametric_valve.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

using testing::runChordfit;
using testing::TempDir;
using testing::tinyConeCase;
using testing::writeText;

CordSet oneTipSet() {
  CordSet set;
  set.tips.push_back({"anterolateral", Eigen::Vector3d(0, 5, -20), std::nullopt});
  return set;
}

TEST(CordPointFile, RoundTripsThePointAndTakesTheVertexOfLargestWeight) {
  TempDir dir;
  CordSet set = oneTipSet();
  Cord cord;
  cord.vertex = 5;
  cord.point = CordPoint{{4, 5, 9}, Eigen::Vector3d(0.25, 0.6, 0.15)};
  cord.rest_length = cord.seed_rest_length = 18.0;
  set.cords.push_back(cord);
  writeCordSet(dir / "cords.json", set);

  // Written with the point; read back bit for bit (the JSON numbers round-trip).
  CordSet read;
  Diagnostics diagnostics;
  ASSERT_TRUE(readCordSet(dir / "cords.json", "cords.json", read, diagnostics));
  ASSERT_EQ(read.cords.size(), 1u);
  ASSERT_TRUE(read.cords[0].point.has_value());
  EXPECT_EQ(read.cords[0].point->vertices, cord.point->vertices);
  EXPECT_EQ(read.cords[0].point->weights, cord.point->weights);
  EXPECT_EQ(read.cords[0].vertex, 5);

  // Without "vertex" the file's point decides it.
  writeText(dir / "bare.json", R"({"format": "chordfit-cordset", "version": 1,
      "tips": [{"name": "anterolateral", "position": [0, 5, -20]}],
      "cords": [{"tip": 0, "point": {"vertices": [4, 5, 9], "weights": [0.25, 0.15, 0.6]},
                 "rest_length_mm": 18.0}]})");
  ASSERT_TRUE(readCordSet(dir / "bare.json", "bare.json", read, diagnostics));
  EXPECT_EQ(read.cords[0].vertex, 9);
}

TEST(CordPointFile, InsertionIsTheWeightedSumOfItsVertices) {
  Eigen::MatrixXd V(3, 3);
  V << 0, 0, 0, 4, 0, 0, 0, 8, 0;
  Cord cord;
  cord.vertex = 0;
  EXPECT_EQ(insertionPosition(cord, V), Eigen::Vector3d(0, 0, 0));
  cord.point = CordPoint{{0, 1, 2}, Eigen::Vector3d(0.5, 0.25, 0.25)};
  EXPECT_TRUE(insertionPosition(cord, V).isApprox(Eigen::Vector3d(1, 2, 0)));
}

class CordPointValidation : public ::testing::Test {
 protected:
  void SetUp() override { writeCase(dir_.path(), tinyConeCase()); }

  // `cord`: the JSON of the one cord. Expects exit 2 and an error line naming the field.
  void expectError(const std::string& cord, const std::string& pattern) {
    writeText(dir_ / "cords.json", R"({"format": "chordfit-cordset", "version": 1,
        "tips": [{"name": "anterolateral", "position": [0, 5, -20]}], "cords": [)" +
                                       cord + "]}");
    nlohmann::json j = nlohmann::json::parse(testing::readText(dir_ / "case.json"));
    j["cords"] = "cords.json";
    writeText(dir_ / "case.json", j.dump(2));
    const testing::CommandResult r = runChordfit("validate '" + dir_.path().string() + "'");
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    const std::regex line("(^|\n)error: cords\\.json: [^\n]*" + pattern);
    EXPECT_TRUE(std::regex_search(r.err, line)) << "stderr was:\n" << r.err;
  }

  TempDir dir_;
};

TEST_F(CordPointValidation, RejectsWeightsThatDoNotSumToOne) {
  expectError(R"({"tip": 0, "point": {"vertices": [9, 10, 11], "weights": [0.5, 0.5, 0.5]},
                  "rest_length_mm": 18.0})",
              "cords\\[0\\]\\.point\\.weights: weights must be >= 0 and sum to 1");
}

TEST_F(CordPointValidation, RejectsANegativeWeight) {
  expectError(R"({"tip": 0, "point": {"vertices": [9, 10, 11], "weights": [1.2, -0.2, 0.0]},
                  "rest_length_mm": 18.0})",
              "cords\\[0\\]\\.point\\.weights: weights must be >= 0 and sum to 1");
}

TEST_F(CordPointValidation, RejectsAPointOnAMissingVertex) {
  expectError(R"({"tip": 0, "point": {"vertices": [9, 10, 9999], "weights": [0.5, 0.5, 0.0]},
                  "rest_length_mm": 18.0})",
              "cords\\[0\\]\\.point: vertex 9999 does not exist");
}

TEST_F(CordPointValidation, RejectsTwoVerticesOrAVertexOutsideThePoint) {
  expectError(R"({"tip": 0, "point": {"vertices": [9, 10], "weights": [0.5, 0.5, 0.0]},
                  "rest_length_mm": 18.0})",
              "cords\\[0\\]\\.point\\.vertices: expected 3 vertex indices, got 2");
  expectError(R"({"tip": 0, "vertex": 3, "point": {"vertices": [9, 10, 11],
                  "weights": [0.5, 0.5, 0.0]}, "rest_length_mm": 18.0})",
              "cords\\[0\\]\\.vertex: vertex 3 is not one of the point's vertices");
}

// The point's keys are checked as the cord's are: a misspelt one is named with the key meant,
// an extra one is not dropped without a word.
TEST_F(CordPointValidation, RejectsAnUnknownPointKeySuggestingTheNearestKnownOne) {
  expectError(R"({"tip": 0, "point": {"vertices": [9, 10, 11], "weigths": [0.5, 0.5, 0.0]},
                  "rest_length_mm": 18.0})",
              "cords\\[0\\]\\.point\\.weigths: unknown key; did you mean \"weights\"\\?");
  expectError(R"({"tip": 0, "point": {"vertices": [9, 10, 11], "weights": [0.5, 0.5, 0.0],
                  "triangle": 4}, "rest_length_mm": 18.0})",
              "cords\\[0\\]\\.point\\.triangle: unknown key\n");
}

// ---------------------------------------------------------------------------------------
// Simulator
// ---------------------------------------------------------------------------------------

ValveCase smallCase() {
  Diagnostics diagnostics;
  const auto loaded =
      loadCase(std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal", diagnostics);
  if (!loaded || !loaded->cords) throw std::runtime_error("bundled case small-normal missing");
  return *loaded;
}

// All weight on one vertex is that vertex's cord: the same closure to the bit.
TEST(CordPointSimulation, AllWeightOnOneVertexClosesExactlyAsTheVertexCord) {
  const ValveCase valve_case = smallCase();
  CordSet at_vertices = *valve_case.cords;
  for (Cord& cord : at_vertices.cords) cord.point.reset();
  CordSet as_points = at_vertices;
  for (Cord& cord : as_points.cords) {
    const int v = cord.vertex;
    cord.point = CordPoint{{v, (v + 1) % 10, (v + 2) % 10}, Eigen::Vector3d(1.0, 0.0, 0.0)};
  }
  const SimulationResult a = simulateClosure(valve_case, at_vertices, SimulationSettings{});
  const SimulationResult b = simulateClosure(valve_case, as_points, SimulationSettings{});
  ASSERT_TRUE(a.ok() && b.ok()) << a.error << b.error;
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_TRUE(a.V == b.V);
}

// A taut inextensible cord holds its insertion point (not a vertex) at its rest length.
TEST(CordPointSimulation, TautPointCordsEndAtTheirRestLength) {
  const ValveCase valve_case = smallCase();
  const CordSet& cords = *valve_case.cords;
  int points = 0;
  for (const Cord& cord : cords.cords) points += cord.point ? 1 : 0;
  ASSERT_EQ(points, static_cast<int>(cords.cords.size())) << "the cohort attaches at points";
  CordSet shorter = cords;
  for (Cord& cord : shorter.cords) cord.rest_length *= 0.8;  // the cohort's cords are ~0.8
  const SimulationResult r = simulateClosure(valve_case, shorter, SimulationSettings{});
  ASSERT_TRUE(r.ok()) << r.error;
  const Eigen::VectorXd spans =
      closedSpans(shorter, cordInsertions(valve_case.mesh, shorter, 0.0), r.V);
  int taut = 0;
  for (std::size_t c = 0; c < shorter.cords.size(); ++c) {
    if (r.cord_force(static_cast<Eigen::Index>(c)) <= 0.0) {
      EXPECT_LE(spans(c), shorter.cords[c].rest_length + 1e-6) << "slack cord " << c;
      continue;
    }
    ++taut;
    EXPECT_NEAR(spans(c), shorter.cords[c].rest_length, 0.05) << "cord " << c;
  }
  EXPECT_GT(taut, 5);
}

// ---------------------------------------------------------------------------------------
// Point attachments of the cohort
// ---------------------------------------------------------------------------------------

struct TwoResolutions {
  ParametricValve fine, coarse;
  std::vector<AnatomicalAttachment> layout;
  TwoResolutions() {
    ValveParameters p;
    p.target_edge_mm = 1.25;
    fine = makeParametricValve(p);
    p.target_edge_mm = 2.5;
    coarse = makeParametricValve(p);
    layout = layoutAttachments(fine);
  }
};

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

// The point of an attachment is the same anatomical place on both meshes, to within the
// meshes' difference in shape, where the nearest vertices are up to half an edge apart.
TEST(PointAttachments, PutACordAtTheSamePlaceOnMeshesOfAnyResolution) {
  const TwoResolutions f;
  const std::vector<CordPoint> fine = pointAttachments(f.fine, f.layout);
  const std::vector<CordPoint> coarse = pointAttachments(f.coarse, f.layout);
  const std::vector<int> fine_v = mapAttachments(f.fine, f.layout);
  const std::vector<int> coarse_v = mapAttachments(f.coarse, f.layout);
  ASSERT_EQ(fine.size(), f.layout.size());
  ASSERT_EQ(coarse.size(), f.layout.size());
  const Eigen::MatrixXd& Vf = f.fine.valve_case.mesh.V;
  const Eigen::MatrixXd& Vc = f.coarse.valve_case.mesh.V;
  std::vector<double> by_point, by_vertex;
  for (std::size_t i = 0; i < f.layout.size(); ++i) {
    by_point.push_back((pointPosition(fine[i], Vf) - pointPosition(coarse[i], Vc)).norm());
    by_vertex.push_back((Vf.row(fine_v[i]) - Vc.row(coarse_v[i])).norm());
    EXPECT_LE(by_point.back(), by_vertex.back() + 0.01) << "attachment " << i;
  }
  // Measured: points median 0.07, largest 0.39 mm (on the P1/P2 cleft, where the coarse free
  // edge cuts the indentation); nearest vertices median 0.5, largest 1.35 mm.
  EXPECT_LT(median(by_point), 0.15);
  EXPECT_LT(*std::max_element(by_point.begin(), by_point.end()), 0.5);
  EXPECT_GT(median(by_vertex), 0.3);  // what the points remove
}

// A repeated vertex would count twice in the constraint's denominator: refused.
TEST(CordPointProblem, RefusesARepeatedVertex) {
  CordPoint point;
  point.vertices = {4, 4, 5};
  point.weights = Eigen::Vector3d(0.3, 0.3, 0.4);
  EXPECT_NE(cordPointProblem(point, 10).find("the three vertices must differ"), std::string::npos);
  point.vertices = {3, 4, 5};
  EXPECT_EQ(cordPointProblem(point, 10), "");
}

TEST(PointAttachments, LieOnTheirLeafletAwayFromTheRingWithValidWeights) {
  const TwoResolutions f;
  for (const ParametricValve* valve : {&f.fine, &f.coarse}) {
    const ValveMesh& mesh = valve->valve_case.mesh;
    const std::set<int> ring(mesh.annulus.data(), mesh.annulus.data() + mesh.annulus.size());
    const std::vector<CordPoint> points = pointAttachments(*valve, f.layout);
    for (std::size_t i = 0; i < points.size(); ++i) {
      EXPECT_EQ(cordPointProblem(points[i], static_cast<int>(mesh.V.rows())), "");
      for (int v : points[i].vertices) {
        EXPECT_EQ(mesh.leaflet(v), f.layout[i].leaflet) << "attachment " << i;
        EXPECT_EQ(ring.count(v), 0u) << "attachment " << i;
      }
      // Its cord's vertex is the point's heaviest and the heuristic measures from the point.
      const CordSet set = attachmentCordSet(f.layout, points);
      EXPECT_EQ(set.cords[i].vertex, largestWeightVertex(points[i]));
    }
  }
}

TEST(PointAttachments, HeuristicRestLengthIsMeasuredFromTheInsertionPoint) {
  const TwoResolutions f;
  ValveCase valve_case = f.coarse.valve_case;
  valve_case.cords = attachmentCordSet(f.layout, pointAttachments(f.coarse, f.layout));
  const CordSet set = heuristicCordSet(valve_case);
  const AnnulusFrame frame = openAnnulusFrame(valve_case.mesh);
  for (const Cord& cord : set.cords) {
    ASSERT_TRUE(cord.point.has_value());
    const Eigen::Vector3d p = insertionPosition(cord, valve_case.mesh.V);
    EXPECT_DOUBLE_EQ(cord.seed_rest_length,
                     heuristicRestLength(p, frame.plane, set.tips[cord.tip].position));
  }
}

}  // namespace
}  // namespace chordfit
