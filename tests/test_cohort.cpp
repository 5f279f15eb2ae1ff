// The synthetic cohort (issue "Synthetic cohort"): presets, anatomical cord attachments,
// true cord scales, and `chordfit make-case` end to end on coarse meshes.
//
// Timing: the make-case runs close coarse truths (edge 3 mm, truth mesh 1.5 mm, ~600
// vertices; a few seconds each). CohortCalibration.* checks one normal and one pathological
// preset at that resolution with a capped step count; the DISABLED_ sweep checks every preset
// and seeds 1-3 (minutes; run with --gtest_also_run_disabled_tests).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <utility>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/case_io.h"
#include "core/closure_model.h"
#include "core/cohort_presets.h"
#include "core/cord_attachments.h"
#include "core/cordset_io.h"
#include "core/mesh_io.h"
#include "core/metrics.h"
#include "core/parametric_valve.h"
#include "core/synthetic_case.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;
using testing::runChordfit;
using testing::TempDir;

// Coarse settings that keep a make-case run to seconds.
constexpr const char* kFastCase = " --edge 3.0 --planes 2";
constexpr double kNoiseMm = 0.3;

using testing::quoted;

// Every regular file under `root`, as paths relative to it.
std::set<std::string> filesUnder(const fs::path& root) {
  std::set<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (entry.is_regular_file()) files.insert(fs::relative(entry.path(), root).string());
  }
  return files;
}

// ---------------------------------------------------------------------------------------
// Presets and true scales (no simulation)
// ---------------------------------------------------------------------------------------

TEST(CohortPresets, CoverTheNormalAndPathologicalCasesOfTheIssue) {
  std::vector<std::string> names;
  for (const CohortPreset& p : cohortPresets()) {
    names.push_back(p.name);
    EXPECT_FALSE(p.summary.empty()) << p.name;
    for (const std::string& s : p.intended_prolapse) EXPECT_GE(mitralSegmentId(s), 0) << s;
    EXPECT_TRUE(std::is_sorted(p.intended_prolapse.begin(), p.intended_prolapse.end()));
  }
  EXPECT_EQ(names, (std::vector<std::string>{"normal-1", "normal-2", "prolapse-P2", "prolapse-A2",
                                             "prolapse-P3", "bileaflet", "flail-P2"}));
  EXPECT_TRUE(findCohortPreset("normal-1")->intended_prolapse.empty());
  EXPECT_EQ(findCohortPreset("flail-P2")->intended_prolapse, std::vector<std::string>{"P2"});
  EXPECT_EQ(findCohortPreset("no-such-preset"), nullptr);
  EXPECT_EQ(mitralSegmentId("A1"), 0);
  EXPECT_EQ(mitralSegmentId("P3"), 5);
  EXPECT_EQ(mitralSegmentId("X2"), -1);
}

TEST(CohortPresets, ASeedIsAPatientAndTheSameSeedTheSamePatient) {
  const CohortPreset& preset = *findCohortPreset("normal-2");
  SeededRandom a(3), b(3), c(4);
  const ValveParameters pa = samplePatientAnatomy(preset, a);
  const ValveParameters pb = samplePatientAnatomy(preset, b);
  const ValveParameters pc = samplePatientAnatomy(preset, c);
  EXPECT_EQ(pa.ap_diameter_mm, pb.ap_diameter_mm);
  EXPECT_EQ(pa.anterior_height_mm, pb.anterior_height_mm);
  EXPECT_NE(pa.ap_diameter_mm, pc.ap_diameter_mm);
  // Within 2.5 SD of the preset's mean.
  const double limit = 2.5 * preset.anatomy_sd + 1e-12;
  EXPECT_LE(std::abs(pc.ap_diameter_mm / preset.anatomy.ap_diameter_mm - 1.0), limit);
  EXPECT_LE(std::abs(pc.posterior_height_mm / preset.anatomy.posterior_height_mm - 1.0), limit);
}

// The anatomical layout of a default valve, decided on a 1 mm mesh.
struct LayoutFixture {
  ParametricValve fine, coarse;
  std::vector<AnatomicalAttachment> layout;
  LayoutFixture() {
    ValveParameters p;
    p.target_edge_mm = 1.0;
    fine = makeParametricValve(p);
    p.target_edge_mm = 2.5;
    coarse = makeParametricValve(p);
    layout = layoutAttachments(fine);
  }
};

TEST(CordAttachments, LayoutHasPrimariesOnBothLeafletsThenSecondariesWithAnatomicalTips) {
  const LayoutFixture f;
  ASSERT_GT(f.layout.size(), 20u);
  std::map<int, int> primaries, secondaries;
  bool seen_secondary = false;
  for (const AnatomicalAttachment& a : f.layout) {
    EXPECT_GE(a.fraction, 0.0);
    EXPECT_LE(a.fraction, 1.0);
    EXPECT_EQ(a.tip, a.fraction <= 0.5 ? 0 : 1);
    if (a.kind == CordKind::kPrimary) {
      EXPECT_FALSE(seen_secondary) << "primaries come first";
      EXPECT_EQ(a.depth_mm, 0.0);
      ++primaries[a.leaflet];
    } else {
      seen_secondary = true;
      EXPECT_EQ(a.depth_mm, 7.0);
      ++secondaries[a.leaflet];
    }
  }
  EXPECT_GE(primaries[0], 4);
  EXPECT_GE(primaries[1], 6);
  EXPECT_GE(secondaries[0], 2);
  EXPECT_GE(secondaries[1], 1);
}

TEST(CordAttachments, MapOneToOneOntoTheRightLeafletAtEveryResolution) {
  const LayoutFixture f;
  for (const ParametricValve* valve : {&f.fine, &f.coarse}) {
    const ValveMesh& mesh = valve->valve_case.mesh;
    const std::vector<int> vertices = mapAttachments(*valve, f.layout);
    ASSERT_EQ(vertices.size(), f.layout.size());
    EXPECT_EQ(std::set<int>(vertices.begin(), vertices.end()).size(), vertices.size());
    const std::set<int> ring(mesh.annulus.data(), mesh.annulus.data() + mesh.annulus.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      EXPECT_EQ(mesh.leaflet(vertices[i]), f.layout[i].leaflet);
      EXPECT_EQ(ring.count(vertices[i]), 0u);
    }
  }
  // The same anatomical place on both meshes: within about a coarse edge.
  const std::vector<int> fine = mapAttachments(f.fine, f.layout);
  const std::vector<int> coarse = mapAttachments(f.coarse, f.layout);
  for (std::size_t i = 0; i < f.layout.size(); ++i) {
    const double d =
        (f.fine.valve_case.mesh.V.row(fine[i]) - f.coarse.valve_case.mesh.V.row(coarse[i])).norm();
    EXPECT_LT(d, 3.0) << "attachment " << i;
  }
}

TEST(CordAttachments, PrimaryPointsLieOnTheFreeEdgeAndSegmentsFollowTheFraction) {
  const LayoutFixture f;
  const Eigen::Vector3d p = attachmentPoint(f.fine, 1, 0.5, 0.0);  // middle of P2, free edge
  double nearest = 1e9;
  for (Eigen::Index i = 0; i < f.fine.free_edge.size(); ++i) {
    nearest = std::min(nearest,
                       (f.fine.valve_case.mesh.V.row(f.fine.free_edge(i)).transpose() - p).norm());
  }
  EXPECT_LT(nearest, 1.0);
  EXPECT_NEAR(leafletHeightAt(f.fine, 1, 0.5), 14.0, 0.5) << "P2 height of the default valve";
  AnatomicalAttachment a;
  a.leaflet = 1;
  a.fraction = 0.5;
  EXPECT_EQ(a.segment(), 4);  // P2
  a.fraction = 0.9;
  EXPECT_EQ(a.segment(), 5);  // P3
}

TEST(TrueCordScales, NormalCordsVarySmoothlyAroundTheBaseAndPathologiesScaleTheirSegment) {
  const LayoutFixture f;
  SeededRandom r1(1);
  const std::vector<double> normal = trueCordScales(*findCohortPreset("normal-1"), f.layout, r1);
  for (std::size_t i = 0; i < f.layout.size(); ++i) {
    const double kind = f.layout[i].kind == CordKind::kSecondary ? kSecondaryCordFactor : 1.0;
    EXPECT_NEAR(normal[i] / (kNormalCordScale * kind), 1.0, 0.09 + 1e-12) << "3 x 3% at most";
  }
  SeededRandom r2(1);
  const CohortPreset& p2 = *findCohortPreset("prolapse-P2");
  const std::vector<double> prolapse = trueCordScales(p2, f.layout, r2);
  for (std::size_t i = 0; i < f.layout.size(); ++i) {
    const double ratio = prolapse[i] / normal[i];
    const AnatomicalAttachment& a = f.layout[i];
    if (a.segment() != mitralSegmentId("P2")) {
      EXPECT_DOUBLE_EQ(ratio, 1.0) << "only P2 cords change";
      continue;
    }
    // Elongated toward the peak scale, most in the middle of P2.
    EXPECT_GE(ratio, 1.0);
    const double peak = p2.segment_scale[4];
    if (std::abs(a.fraction - 0.5) < 0.05) {
      EXPECT_NEAR(prolapse[i], peak, 0.1 * peak + p2.scale_spread);
    }
  }
  SeededRandom r3(1);
  std::vector<bool> ruptured;
  const std::vector<double> flail =
      trueCordScales(*findCohortPreset("flail-P2"), f.layout, r3, &ruptured);
  int count = 0;
  for (std::size_t i = 0; i < f.layout.size(); ++i) {
    if (!ruptured[i]) continue;
    ++count;
    EXPECT_EQ(f.layout[i].kind, CordKind::kPrimary);
    EXPECT_EQ(f.layout[i].segment(), mitralSegmentId("P2"));
    EXPECT_EQ(flail[i], kRupturedCordScale);
  }
  EXPECT_GE(count, 1);
  EXPECT_LE(count, 2);
}

// ---------------------------------------------------------------------------------------
// make-case end to end
// ---------------------------------------------------------------------------------------

TEST(MakeCaseCli, ListPrintsEveryPreset) {
  const auto r = runChordfit("make-case --list");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const CohortPreset& p : cohortPresets()) {
    EXPECT_NE(r.out.find(p.name + " "), std::string::npos) << p.name;
  }
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'),
            static_cast<long>(cohortPresets().size()));
}

TEST(MakeCaseCli, RejectsBadPresetsAndOptionsWithExitTwo) {
  TempDir dir;
  auto r = runChordfit("make-case --preset prolapse-Q9 --out " + quoted(dir / "c"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: make-case: --preset: unknown preset \"prolapse-Q9\""),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("normal-1"), std::string::npos) << "lists the known presets";
  r = runChordfit("make-case --out " + quoted(dir / "c"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: make-case: --preset"), std::string::npos) << r.err;
  r = runChordfit("make-case --preset normal-1 --out " + quoted(dir / "c") + " --planes 0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: make-case: --planes"), std::string::npos) << r.err;
  r = runChordfit("make-case --preset normal-1 --out " + quoted(dir / "c") + " --edge 0.5");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: make-case: --edge: must be in [1, 5] mm, got 0.5 (it gives a "
                       "truth mesh finer than 0.5 mm"),
            std::string::npos)
      << r.err;
  r = runChordfit("make-case --preset normal-1 --out " + quoted(dir / "c") + " --dropout 1.5");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: make-case: --dropout"), std::string::npos) << r.err;
  r = runChordfit("make-case --preset normal-1 --out " + quoted(dir / "c") + " --seed -1");
  EXPECT_EQ(r.exit_code, 2) << "an unsigned seed must not wrap -1 to 2^64 - 1";
  EXPECT_NE(r.err.find("--seed: must be a non-negative integer"), std::string::npos) << r.err;
  r = runChordfit("make-case --preset normal-1 --out " + quoted(dir / "c") +
                  " --seed 99999999999999999999");
  EXPECT_EQ(r.exit_code, 2) << "nor saturate a seed past 2^64 - 1 to 2^64 - 1";
  EXPECT_NE(r.err.find("--seed: must be at most 18446744073709551615, got 99999999999999999999"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "c" / "case.json"));
}

// One make-case run shared by the end-to-end checks below.
class MakeCaseRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    result_ = new testing::CommandResult(runChordfit(
        "make-case --preset prolapse-P2 --seed 5 --out " + quoted(dir_->path() / "a") + kFastCase));
  }
  static void TearDownTestSuite() {
    delete result_;
    delete dir_;
  }
  void SetUp() override { ASSERT_EQ(result_->exit_code, 0) << result_->err; }
  static fs::path caseDir() { return dir_->path() / "a"; }
  static TempDir* dir_;
  static testing::CommandResult* result_;
};
TempDir* MakeCaseRun::dir_ = nullptr;
testing::CommandResult* MakeCaseRun::result_ = nullptr;

// --edge 0 used to be told "must be in [0.5, 5] mm", and then 0.5 was refused too: the range
// stated is the one the command takes.
TEST(MakeCaseCli, AnEdgeOutsideTheRangeIsToldTheRangeTheCommandTakes) {
  TempDir dir;
  for (const char* edge : {"0", "0.5", "0.99", "5.5", "nan"}) {
    const auto r =
        runChordfit("make-case --preset normal-1 --out " + quoted(dir / "c") + " --edge " + edge);
    EXPECT_EQ(r.exit_code, 2) << edge;
    EXPECT_NE(r.err.find("error: make-case: --edge: must be in [1, 5] mm, got "), std::string::npos)
        << edge << ": " << r.err;
    EXPECT_EQ(r.err.find("[0.5, 5]"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir / "c" / "case.json"));
}

// A case over an earlier one: the earlier run's files the new case lacks go (here the lesion
// tissue of a prolapse-A2 truth under a normal one), the user's stay.
TEST(MakeCaseCli, AnEarlierCasesFilesTheNewOneLacksAreRemovedAndTheUsersKept) {
  TempDir dir;
  const fs::path case_dir = dir / "c";
  auto r =
      runChordfit("make-case --preset prolapse-A2 --quiet --out " + quoted(case_dir) + kFastCase);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(case_dir / "truth" / "case" / "tissue.json"));
  testing::writeText(case_dir / "truth" / "notes.txt", "the user's");
  r = runChordfit("make-case --preset normal-1 --quiet --out " + quoted(case_dir) + kFastCase);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("; removed truth/case/tissue.json (an earlier run's)"), std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(case_dir / "truth" / "case" / "tissue.json"));
  EXPECT_EQ(testing::readText(case_dir / "truth" / "notes.txt"), "the user's");
  const auto truth = nlohmann::json::parse(testing::readText(case_dir / "truth" / "truth.json"));
  EXPECT_EQ(truth["preset"], "normal-1");
  EXPECT_EQ(runChordfit("validate " + quoted(case_dir / "truth" / "case")).exit_code, 0);
}

TEST_F(MakeCaseRun, WritesALoadableCaseWithTracingsAndTheHeuristicSeedCords) {
  Diagnostics diagnostics;
  const auto c = loadCase(caseDir(), diagnostics);
  ASSERT_TRUE(c.has_value());
  EXPECT_TRUE(diagnostics.ok());
  EXPECT_FALSE(c->tracings.empty());
  for (const Tracing& t : c->tracings) {
    EXPECT_GE(t.points.rows(), 2);
    EXPECT_GE(t.leaflet, 0) << "every tracing is labelled";
  }
  ASSERT_TRUE(c->cords.has_value());
  for (const Cord& cord : c->cords->cords) {
    EXPECT_EQ(cord.provenance, Provenance::kHeuristic);
    EXPECT_DOUBLE_EQ(cord.scale(), 1.0);
  }
  // The truth case corresponds cord by cord.
  Diagnostics truth_diagnostics;
  const auto truth = loadCase(caseDir() / "truth" / "case", truth_diagnostics);
  ASSERT_TRUE(truth.has_value());
  ASSERT_TRUE(truth->cords.has_value());
  ASSERT_EQ(truth->cords->cords.size(), c->cords->cords.size());
  EXPECT_GT(truth->mesh.V.rows(), 3 * c->mesh.V.rows()) << "truth mesh about twice as fine";
  for (std::size_t i = 0; i < c->cords->cords.size(); ++i) {
    EXPECT_EQ(truth->cords->cords[i].kind, c->cords->cords[i].kind);
    EXPECT_EQ(truth->cords->cords[i].tip, c->cords->cords[i].tip);
    EXPECT_EQ(truth->mesh.leaflet(truth->cords->cords[i].vertex),
              c->mesh.leaflet(c->cords->cords[i].vertex));
  }
  // Lesion tissue (none in prolapse-P2) would be in the truth case only.
  EXPECT_EQ(c->tissue_stiffness.size(), 0);
  for (const char* name : {"cords.json", "case_cords.json", "closed.ply", "closed.vtk",
                           "metrics.json", "truth.json", "cross_sections.svg", "enface.svg"}) {
    EXPECT_TRUE(fs::exists(caseDir() / "truth" / name)) << name;
  }
  // The true cords on the case mesh: the case's attachments, the truth's lengths and tips.
  CordSet on_case;
  Diagnostics problems;
  ASSERT_TRUE(
      readCordSet(caseDir() / "truth" / "case_cords.json", "case_cords.json", on_case, problems));
  ASSERT_EQ(on_case.cords.size(), c->cords->cords.size());
  for (std::size_t i = 0; i < on_case.cords.size(); ++i) {
    EXPECT_EQ(on_case.cords[i].vertex, c->cords->cords[i].vertex);
    EXPECT_EQ(on_case.cords[i].rest_length, truth->cords->cords[i].rest_length);
    EXPECT_EQ(on_case.cords[i].provenance, truth->cords->cords[i].provenance) << i;
  }
  // Each cord's tension at the true closed state: some taut, none negative (a cord only pulls).
  const auto truth_json =
      nlohmann::json::parse(testing::readText(caseDir() / "truth" / "truth.json"));
  int taut = 0;
  for (const auto& cord : truth_json["cords"]) {
    const double tension = cord.at("true_closed_tension_n").get<double>();
    EXPECT_GE(tension, 0.0);
    taut += tension > 0.0;
  }
  EXPECT_GT(taut, 0);
  EXPECT_LT(taut, static_cast<int>(truth_json["cords"].size())) << "some cords are slack";
  const auto validated = runChordfit("validate " + quoted(caseDir()));
  EXPECT_EQ(validated.exit_code, 0) << validated.out << validated.err;
}

TEST_F(MakeCaseRun, KeepsEveryTruthInsideTheTruthFolder) {
  const std::string case_json = testing::readText(caseDir() / "case.json");
  EXPECT_EQ(case_json.find("truth"), std::string::npos) << case_json;
  for (const std::string& file : filesUnder(caseDir())) {
    if (file.rfind("truth", 0) == 0) continue;
    const std::string text = testing::readText(caseDir() / file);
    EXPECT_EQ(text.find("truth"), std::string::npos) << file << " mentions the truth";
  }
}

TEST_F(MakeCaseRun, TracingsLieWithinTheNoiseOfTheTrueClosedMesh) {
  Diagnostics diagnostics;
  const auto c = loadCase(caseDir(), diagnostics);
  ASSERT_TRUE(c.has_value());
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  ASSERT_TRUE(readMesh(caseDir() / "truth" / "closed.ply", V, F, diagnostics));
  const Eigen::VectorXd d = pointToSurfaceDistances(V, F, stackTracingPoints(c->tracings));
  EXPECT_LT(d.mean(), 2.0 * kNoiseMm + 0.1);
  EXPECT_GT(d.mean(), 0.2 * kNoiseMm) << "noise was added";
  const auto metrics = nlohmann::json::parse(testing::readText(caseDir() / "truth/metrics.json"));
  EXPECT_NEAR(metrics["mean_mm"].get<double>(), d.mean(), 1e-6) << "noise floor recorded";
}

// The same seed gives the same files, also with another thread count for the truth closure
// (the fixture's run uses the default, 2).
TEST_F(MakeCaseRun, SameSeedGivesByteIdenticalFiles) {
  const fs::path again = dir_->path() / "b";
  const auto r = runChordfit("make-case --preset prolapse-P2 --seed 5 --out " + quoted(again) +
                             kFastCase + " --threads 1 --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::set<std::string> files = filesUnder(caseDir());
  EXPECT_EQ(filesUnder(again), files);
  for (const std::string& file : files) {
    EXPECT_TRUE(testing::readText(caseDir() / file) == testing::readText(again / file)) << file;
  }
}

TEST(MakeCase, AnotherSeedIsAnotherPatient) {
  // Geometry only (no closure): the anatomy of two seeds of one preset differs.
  const CohortPreset& preset = *findCohortPreset("prolapse-P2");
  SeededRandom a = SeededRandom::stream(5, 1), b = SeededRandom::stream(6, 1);
  ValveParameters pa = samplePatientAnatomy(preset, a), pb = samplePatientAnatomy(preset, b);
  pa.target_edge_mm = pb.target_edge_mm = 3.0;
  const ValveMesh ma = makeParametricValve(pa).valve_case.mesh;
  const ValveMesh mb = makeParametricValve(pb).valve_case.mesh;
  const bool same_size = ma.V.rows() == mb.V.rows();
  EXPECT_TRUE(!same_size || !ma.V.isApprox(mb.V)) << "different seed, same geometry";
}

// The open mesh of a preset's mean anatomy at the given edge length.
ValveMesh presetMesh(const CohortPreset& preset, double edge_mm) {
  ValveParameters anatomy = preset.anatomy;
  anatomy.target_edge_mm = edge_mm;
  return makeParametricValve(anatomy).valve_case.mesh;
}

TEST(LesionTissue, SoftAtTheLesionCentreHealthyElsewhereAndOnlyInTheTruth) {
  const CohortPreset& preset = *findCohortPreset("prolapse-A2");
  const ValveMesh mesh = presetMesh(preset, 2.0);
  const Eigen::VectorXd factors = lesionTissueStiffness(preset, mesh);
  ASSERT_EQ(factors.size(), mesh.V.rows());
  const Eigen::VectorXi segments = openStateSegments(mesh);
  double softest_a2 = 1.0;
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v) {
    EXPECT_GE(factors(v), preset.lesion_stiffness - 1e-12);
    EXPECT_LE(factors(v), 1.0);
    if (mesh.leaflet(v) == 1) {
      EXPECT_EQ(factors(v), 1.0) << "posterior vertex " << v;
    }
    if (segments(v) == mitralSegmentId("A2")) softest_a2 = std::min(softest_a2, factors(v));
  }
  EXPECT_LT(softest_a2, 1.5 * preset.lesion_stiffness) << "the A2 centre is lesion tissue";
  EXPECT_EQ(lesionTissueStiffness(*findCohortPreset("normal-1"), mesh).size(), 0);
}

// The truth closure retries a divergence with half the time step, at most kTruthRetries
// times, and gives up at once on any other error.
TEST(TruthClosure, RetriesADivergenceWithHalfTheTimeStep) {
  const auto diverging = [](int failures, std::vector<SimulationSettings>* seen) {
    return [failures, seen](const SimulationSettings& settings) {
      seen->push_back(settings);
      SimulationResult r;
      if (static_cast<int>(seen->size()) <= failures) {
        r.error = "simulation diverged";
        r.diverged = true;
      }
      return r;
    };
  };
  std::vector<SimulationSettings> seen;
  SimulationSettings settings = truthSimulationSettings();
  int retries = -1;
  SimulationResult r = closeTruthWithRetries(diverging(1, &seen), settings, retries);
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(retries, 1);
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_DOUBLE_EQ(seen[1].stiffness_ratio, 0.25 * seen[0].stiffness_ratio) << "dt halves";
  EXPECT_EQ(seen[1].max_steps, 2 * seen[0].max_steps) << "the same simulated time";
  EXPECT_DOUBLE_EQ(settings.stiffness_ratio, seen[1].stiffness_ratio) << "what was used";

  seen.clear();
  settings = truthSimulationSettings();
  settings.dt_ms = 0.01;
  r = closeTruthWithRetries(diverging(100, &seen), settings, retries);
  EXPECT_TRUE(r.diverged);
  EXPECT_EQ(retries, kTruthRetries);
  ASSERT_EQ(seen.size(), static_cast<std::size_t>(kTruthRetries + 1));
  EXPECT_DOUBLE_EQ(seen.back().dt_ms, 0.01 / (1 << kTruthRetries)) << "an explicit dt halves";

  seen.clear();
  settings = truthSimulationSettings();
  const auto invalid = [&seen](const SimulationSettings& s) {
    seen.push_back(s);
    SimulationResult bad;
    bad.error = "settings: pressure_mmhg: out of range";
    return bad;
  };
  r = closeTruthWithRetries(invalid, settings, retries);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(retries, 0);
  EXPECT_EQ(seen.size(), 1u) << "bad input is not retried";
}

// bileaflet elongates A2 and P2 cords but has lesion tissue in A2 only (lesion_segments).
TEST(LesionTissue, OnlyInTheListedSegments) {
  const CohortPreset& preset = *findCohortPreset("bileaflet");
  const ValveMesh mesh = presetMesh(preset, 2.5);
  const Eigen::VectorXd factors = lesionTissueStiffness(preset, mesh);
  ASSERT_EQ(factors.size(), mesh.V.rows());
  double softest_a2 = 1.0;
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v) {
    if (mesh.leaflet(v) == 1) {
      EXPECT_EQ(factors(v), 1.0) << "posterior vertex " << v;
    }
    if (mesh.leaflet(v) == 0) softest_a2 = std::min(softest_a2, factors(v));
  }
  EXPECT_LT(softest_a2, 1.5 * preset.lesion_stiffness);
  // Without the list every elongated segment gets the tissue.
  CohortPreset every = preset;
  every.lesion_segments = {};
  const Eigen::VectorXd both = lesionTissueStiffness(every, mesh);
  double softest_posterior = 1.0;
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v) {
    if (mesh.leaflet(v) == 1) softest_posterior = std::min(softest_posterior, both(v));
  }
  EXPECT_LT(softest_posterior, 1.5 * preset.lesion_stiffness);
}

// truth/case must redo the truth: its simulation settings are the truth's solver settings,
// the 6 ms pressure ramp the cohort was calibrated with included (the default is 10 ms).
TEST(TruthCase, CarriesTheTruthSolverSettings) {
  SyntheticCaseOptions options;
  options.preset = "normal-1";
  options.edge_mm = 3.0;
  options.tracing.planes = 2;
  SimulationSettings settings = truthSimulationSettings();
  settings.max_steps = 400;  // only the settings matter here (the 6 ms ramp: ~200 steps)
  options.truth_settings = settings;
  const SyntheticCase s = makeSyntheticCase(options);
  Diagnostics diagnostics;
  const SimulationSettings parsed = settingsFromJson(s.truth_case.simulation_json, diagnostics);
  EXPECT_TRUE(diagnostics.ok());
  EXPECT_EQ(parsed.ramp_ms, 6.0);
  EXPECT_NE(parsed.ramp_ms, SimulationSettings{}.ramp_ms);
  EXPECT_EQ(parsed.tolerance_mm, settings.tolerance_mm);
  EXPECT_EQ(parsed.window, settings.window);
  EXPECT_EQ(parsed.max_steps, settings.max_steps);
  EXPECT_EQ(parsed.stiffness_ratio, SimulationSettings{}.stiffness_ratio);

  // A truth closed again after a divergence ran with a shorter step (halvedTimeStep), which
  // its case must carry too (it did not before 2026-11-27: truth/case then re-simulated with
  // the default step).
  options.truth_settings = halvedTimeStep(settings);
  const SyntheticCase retried = makeSyntheticCase(options);
  const SimulationSettings halved =
      settingsFromJson(retried.truth_case.simulation_json, diagnostics);
  EXPECT_TRUE(diagnostics.ok());
  EXPECT_EQ(halved.stiffness_ratio, 0.25 * SimulationSettings{}.stiffness_ratio);
  EXPECT_EQ(halved.max_steps, 2 * settings.max_steps);
  EXPECT_EQ(halved.cord_insertion_radius_mm, 0.0);
}

// A truth finer than the committed cohort's (1.25 and 0.75 mm) spreads its cords' pull over
// 2 mm of leaflet (its point insertions diverged at 0.5 mm), and its case carries that.
TEST(TruthCase, AFineTruthSpreadsItsCordInsertions) {
  EXPECT_EQ(truthSimulationSettings(1.25).cord_insertion_radius_mm, 0.0);
  EXPECT_EQ(truthSimulationSettings(0.75).cord_insertion_radius_mm, 0.0);
  EXPECT_EQ(truthSimulationSettings(0.5).cord_insertion_radius_mm, 2.0);
  SyntheticCaseOptions options;
  options.preset = "normal-1";
  options.edge_mm = 3.0;
  options.tracing.planes = 2;
  SimulationSettings settings = truthSimulationSettings(0.5);
  settings.max_steps = 400;  // only the settings matter here
  options.truth_settings = settings;
  const SyntheticCase s = makeSyntheticCase(options);
  Diagnostics diagnostics;
  EXPECT_EQ(settingsFromJson(s.truth_case.simulation_json, diagnostics).cord_insertion_radius_mm,
            2.0);
  EXPECT_TRUE(diagnostics.ok());
}

// The truth's valve at another resolution (mesh-convergence studies): at the truth's own
// edge it is the truth case; at the case edge it has the case mesh and the case's cord
// points, but keeps the truth's rest lengths, tips and lesion tissue.
TEST(TruthCaseAtEdge, IsTheSamePhysicalValveOnAnotherMesh) {
  SyntheticCaseOptions options;
  options.preset = "prolapse-A2";  // lesion tissue as well as cords
  options.seed = 2;
  options.edge_mm = 3.0;
  options.tracing.planes = 2;
  SimulationSettings settings = truthSimulationSettings();
  settings.max_steps = 400;  // only the geometry and cords matter here (past the ramp)
  options.truth_settings = settings;
  const SyntheticCase s = makeSyntheticCase(options);
  const CordSet& truth_cords = *s.truth_case.cords;

  const ValveCase same = truthCaseAtEdge(s, options.edge_mm * options.truth_edge_ratio);
  EXPECT_EQ(same.mesh.V, s.truth_case.mesh.V);
  EXPECT_EQ(same.tissue_stiffness, s.truth_case.tissue_stiffness);
  EXPECT_EQ(same.tracings.size(), s.truth_case.tracings.size());
  ASSERT_EQ(same.cords->cords.size(), truth_cords.cords.size());
  for (std::size_t i = 0; i < truth_cords.cords.size(); ++i) {
    EXPECT_EQ(same.cords->cords[i].vertex, truth_cords.cords[i].vertex) << "cord " << i;
    ASSERT_EQ(same.cords->cords[i].point.has_value(), truth_cords.cords[i].point.has_value());
    if (truth_cords.cords[i].point) {
      EXPECT_EQ(same.cords->cords[i].point->weights, truth_cords.cords[i].point->weights);
    }
  }

  const ValveCase coarse = truthCaseAtEdge(s, options.edge_mm);
  EXPECT_EQ(coarse.mesh.V, s.valve_case.mesh.V) << "the case mesh";
  ASSERT_EQ(coarse.cords->cords.size(), truth_cords.cords.size());
  ASSERT_EQ(coarse.cords->tips.size(), truth_cords.tips.size());
  for (std::size_t t = 0; t < truth_cords.tips.size(); ++t) {
    EXPECT_EQ(coarse.cords->tips[t].position, truth_cords.tips[t].position) << "true tip";
  }
  for (std::size_t i = 0; i < truth_cords.cords.size(); ++i) {
    const Cord& cord = coarse.cords->cords[i];
    EXPECT_EQ(cord.rest_length, truth_cords.cords[i].rest_length) << "true length, cord " << i;
    EXPECT_EQ(cord.vertex, s.case_vertices[i]) << "case attachment, cord " << i;
    ASSERT_TRUE(cord.point.has_value());
    EXPECT_EQ(cord.point->vertices, s.case_points[i].vertices);
    EXPECT_EQ(cord.point->weights, s.case_points[i].weights);
  }
  ASSERT_EQ(coarse.tissue_stiffness.size(), coarse.mesh.V.rows());
  EXPECT_LT(coarse.tissue_stiffness.minCoeff(), 0.5) << "the lesion is there";
  EXPECT_THROW(truthCaseAtEdge(s, 0.0), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------
// Calibration: the truths prolapse exactly where the preset says.
// ---------------------------------------------------------------------------------------

// A preset's truth at the calibration resolution (edge 3 mm, truth 1.5 mm), one plane.
// `max_steps` caps the closure: while the simulator does not meet its equilibrium criterion
// on some truths (experiments/README.md), their shape (segment heights to 0.1 mm) has settled
// long before the cap, and the cap keeps the test to seconds.
SyntheticCase coarseTruth(const CohortPreset& preset, std::uint64_t seed, int max_steps) {
  SyntheticCaseOptions options;
  options.preset = preset.name;
  options.seed = seed;
  options.edge_mm = 3.0;
  options.tracing.planes = 1;
  SimulationSettings settings = truthSimulationSettings();
  settings.max_steps = std::min(settings.max_steps, max_steps);
  options.truth_settings = settings;
  return makeSyntheticCase(options);
}

std::string describe(const SyntheticCase& s) {
  std::string text = s.preset.name + " seed " + std::to_string(s.options.seed) + ": prolapse [";
  for (const std::string& name : s.truth_metrics.mesh_prolapse.segments) text += name + " ";
  return text + "], max height " + std::to_string(s.truth_metrics.mesh_prolapse.max_height_mm) +
         " mm, converged " + std::to_string(s.truth_result.converged);
}

TEST(CohortCalibration, NormalTruthClosesWithoutProlapse) {
  const SyntheticCase s = coarseTruth(*findCohortPreset("normal-1"), 1, 2000);
  EXPECT_TRUE(s.truth_metrics.mesh_prolapse.segments.empty()) << describe(s);
  EXPECT_LT(s.truth_metrics.mesh_prolapse.max_height_mm, 2.0) << describe(s);
}

TEST(CohortCalibration, P2TruthProlapsesInP2Only) {
  const SyntheticCase s = coarseTruth(*findCohortPreset("prolapse-P2"), 1, 3000);
  EXPECT_EQ(s.truth_metrics.mesh_prolapse.segments, std::vector<std::string>{"P2"}) << describe(s);
  // A clinical prolapse: a few mm above the annulus, not a numerical whisker.
  EXPECT_GT(s.truth_metrics.mesh_prolapse.max_height_mm, 3.0) << describe(s);
}

// A2 and P3 prolapse through their soft lesion tissue (cohort_presets.h, lesion_stiffness).
TEST(CohortCalibration, A2TruthProlapsesInA2Only) {
  const SyntheticCase s = coarseTruth(*findCohortPreset("prolapse-A2"), 3, 3000);
  EXPECT_EQ(s.truth_metrics.mesh_prolapse.segments, std::vector<std::string>{"A2"}) << describe(s);
  EXPECT_GT(s.truth_metrics.mesh_prolapse.max_height_mm, 2.5) << describe(s);
  EXPECT_EQ(s.truth_case.tissue_stiffness.size(), s.truth_case.mesh.V.rows());
  EXPECT_EQ(s.valve_case.tissue_stiffness.size(), 0) << "the fitter assumes uniform tissue";
}

TEST(CohortCalibration, P3TruthProlapsesInP3Only) {
  const SyntheticCase s = coarseTruth(*findCohortPreset("prolapse-P3"), 3, 3000);
  EXPECT_EQ(s.truth_metrics.mesh_prolapse.segments, std::vector<std::string>{"P3"}) << describe(s);
  EXPECT_GT(s.truth_metrics.mesh_prolapse.max_height_mm, 3.0) << describe(s);
}

// The benchmark's truths (experiments/, every preset, seeds 1-3, case edge 2.5 mm, truth
// 1.25 mm, the truth solver settings uncapped; ~20 s): each prolapses exactly in its intended
// segments, the normal ones nowhere. bileaflet seed 2 lifted A1 to 2.35 mm beside A2 with the
// preset's commissures at 10 mm; with 11 mm it stays at ~1 mm (experiments/README.md,
// "Calibration").
TEST(CohortCalibration, EveryBenchmarkTruthProlapsesExactlyWhereIntended) {
  for (const CohortPreset& preset : cohortPresets()) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      SyntheticCaseOptions options;
      options.preset = preset.name;
      options.seed = seed;
      options.edge_mm = 2.5;
      options.tracing.planes = 1;
      const SyntheticCase s = makeSyntheticCase(options);
      EXPECT_EQ(s.truth_metrics.mesh_prolapse.segments, preset.intended_prolapse) << describe(s);
      EXPECT_TRUE(s.truth_result.converged) << describe(s);
      // No leaflet passes through another or itself, prolapsing flaps included.
      EXPECT_EQ(s.truth_metrics.self_intersections, 0) << describe(s);
    }
  }
}

// The fine truth of normal-1 seed 1 at the make-case default edge (1.5 mm, truth 0.75 mm,
// 2,141 vertices): with its cords' tension at their insertion points (the default), the tents
// of the heavily loaded secondaries (15-20 N) cycle, the largest step at 0.02-0.08 mm, and the
// closure runs to the step cap; spread over 2 mm (SimulationSettings::cord_insertion_radius_mm,
// core/cord_insertion.h) it settles (docs/performance.md, "Cord insertion patch"). ~8 s.
TEST(CohortTruthClosure, TheFineNormalTruthSettlesOnlyWithTheInsertionPatch) {
  SyntheticCaseOptions options;
  options.preset = "normal-1";
  options.seed = 1;
  options.tracing.planes = 1;
  SimulationSettings point = truthSimulationSettings();
  point.max_steps = 3000;
  options.truth_settings = point;
  const SyntheticCase at_points = makeSyntheticCase(options);
  EXPECT_FALSE(at_points.truth_result.converged) << describe(at_points);
  EXPECT_GT(at_points.truth_result.max_displacement_mm, 10.0 * point.tolerance_mm);
  SimulationSettings spread = truthSimulationSettings();
  spread.cord_insertion_radius_mm = 2.0;
  const SimulationResult closed =
      simulateClosure(at_points.truth_case, *at_points.truth_case.cords, spread);
  ASSERT_TRUE(closed.ok()) << closed.error;
  EXPECT_TRUE(closed.converged) << closed.steps << " steps, last step "
                                << closed.max_displacement_mm << " mm";
}

// Every preset, seeds 1-3 (~10-20 s): the calibration of experiments/README.md holds. Guards it
// against simulator and generator changes. The one known miss, prolapse-P3 seed 1, lifts A3
// as well as P3; for it the intended segment must still be among the prolapsing ones.
TEST(CohortCalibration, EveryPresetAndSeedProlapsesWhereIntended) {
  const std::set<std::pair<std::string, std::uint64_t>> lifts_a_neighbour = {{"prolapse-P3", 1}};
  for (const CohortPreset& preset : cohortPresets()) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      const SyntheticCase s = coarseTruth(preset, seed, 3000);
      const std::vector<std::string>& found = s.truth_metrics.mesh_prolapse.segments;
      if (lifts_a_neighbour.count({preset.name, seed})) {
        EXPECT_TRUE(std::includes(found.begin(), found.end(), preset.intended_prolapse.begin(),
                                  preset.intended_prolapse.end()))
            << describe(s);
      } else {
        EXPECT_EQ(found, preset.intended_prolapse) << describe(s);
      }
    }
  }
}

}  // namespace
}  // namespace chordfit
