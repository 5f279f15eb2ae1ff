// Importing a bare valve mesh (core/case_import.h, chordfit import-mesh): on the parametric
// valve, whose ring, labels and closed annulus are known, the derived ones must match; bad
// landmarks and meshes are reported in words; the command writes a loadable case or nothing.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "core/case_import.h"
#include "core/case_io.h"
#include "core/curve_io.h"
#include "core/mesh_io.h"
#include "core/mesh_topology.h"
#include "core/parametric_valve.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;
using testing::quoted;
using testing::runChordfit;
using testing::TempDir;

constexpr double kMinLabelAgreement = 0.97;  // all but about one column at a commissure
constexpr double kClosedRingToleranceMm = 0.3;

ParametricValve valve() {
  ValveParameters p;
  p.target_edge_mm = 2.0;
  return makeParametricValve(p);
}

// The landmarks a user would place: the two commissures (where the ring's label changes; the
// anterolateral one toward +y) and the anterior annulus vertex farthest toward +x.
ImportLandmarks landmarksOf(const ValveMesh& mesh) {
  const Eigen::Index n = mesh.annulus.size();
  std::vector<Eigen::Vector3d> commissures;
  Eigen::Vector3d anterior = Eigen::Vector3d::Constant(-1e9);
  for (Eigen::Index k = 0; k < n; ++k) {
    const int v = mesh.annulus(k), next = mesh.annulus((k + 1) % n);
    if (mesh.leaflet(v) != mesh.leaflet(next)) commissures.push_back(mesh.V.row(v));
    if (mesh.leaflet(v) == 0 && mesh.V(v, 0) > anterior.x()) anterior = mesh.V.row(v);
  }
  EXPECT_EQ(commissures.size(), 2u);
  ImportLandmarks l;
  const bool first_lateral = commissures[0].y() > commissures[1].y();
  l.anterolateral = commissures[first_lateral ? 0 : 1];
  l.posteromedial = commissures[first_lateral ? 1 : 0];
  l.anterior = anterior;
  return l;
}

double labelAgreement(const Eigen::VectorXi& a, const Eigen::VectorXi& b) {
  return static_cast<double>((a.array() == b.array()).count()) / static_cast<double>(a.size());
}

TEST(CaseImport, RecoversTheRingLabelsAndClosedAnnulusOfTheParametricValve) {
  const ParametricValve pv = valve();
  const ValveCase& truth = pv.valve_case;
  const ImportedCase imported = importValveCase(truth.mesh.V, truth.mesh.F, landmarksOf(truth.mesh),
                                                truth.annulus_closed, "imported");
  ASSERT_TRUE(imported.ok()) << imported.error;
  const ValveMesh& mesh = imported.valve_case.mesh;
  EXPECT_EQ(mesh.V, truth.mesh.V);
  EXPECT_EQ(mesh.F, truth.mesh.F);
  EXPECT_GE(labelAgreement(mesh.leaflet, truth.mesh.leaflet), kMinLabelAgreement);
  EXPECT_NEAR(imported.anterior_fraction, 1.0 / 3.0, 0.03);
  EXPECT_LT(imported.commissure_distance_mm[0], 1e-9);
  // The same ring, and each ring vertex's closed position as the valve's own.
  ASSERT_EQ(mesh.annulus.size(), truth.mesh.annulus.size());
  for (Eigen::Index k = 0; k < mesh.annulus.size(); ++k) {
    Eigen::Index j = 0;
    ASSERT_TRUE((truth.mesh.annulus.array() == mesh.annulus(k)).maxCoeff(&j))
        << "ring vertex " << mesh.annulus(k);
    EXPECT_LT((imported.valve_case.annulus_closed.row(k) - truth.annulus_closed.row(j)).norm(),
              kClosedRingToleranceMm)
        << "ring vertex " << mesh.annulus(k);
  }
}

// A segmented surface is never as regular as the parametric one: jitter every vertex by up to
// 0.3 mm (a fifth of an edge); the labels must not care.
TEST(CaseImport, LabelsSurviveAnIrregularSurface) {
  const ValveCase& truth = valve().valve_case;
  Eigen::MatrixXd V = truth.mesh.V;
  std::uint64_t state = 12345;
  for (Eigen::Index i = 0; i < V.size(); ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;  // LCG (Knuth MMIX)
    V(i) += 0.3 * (2.0 * static_cast<double>(state >> 11) / 9007199254740992.0 - 1.0);
  }
  const ImportedCase imported =
      importValveCase(V, truth.mesh.F, landmarksOf(truth.mesh), Eigen::MatrixXd(), "jittered");
  ASSERT_TRUE(imported.ok()) << imported.error;
  EXPECT_GE(labelAgreement(imported.valve_case.mesh.leaflet, truth.mesh.leaflet),
            kMinLabelAgreement);
  EXPECT_LT(imported.commissure_distance_mm[0], 0.6);
}

TEST(CaseImport, CommissureOrderDoesNotMatterAndNoCurveMeansAStaticAnnulus) {
  const ValveCase& truth = valve().valve_case;
  ImportLandmarks swapped = landmarksOf(truth.mesh);
  std::swap(swapped.anterolateral, swapped.posteromedial);
  const ImportedCase imported =
      importValveCase(truth.mesh.V, truth.mesh.F, swapped, Eigen::MatrixXd(), "static");
  ASSERT_TRUE(imported.ok()) << imported.error;
  EXPECT_GE(labelAgreement(imported.valve_case.mesh.leaflet, truth.mesh.leaflet),
            kMinLabelAgreement);
  for (Eigen::Index k = 0; k < imported.valve_case.mesh.annulus.size(); ++k) {
    EXPECT_EQ(imported.valve_case.annulus_closed.row(k),
              truth.mesh.V.row(imported.valve_case.mesh.annulus(k)));
  }
  EXPECT_EQ(imported.closed_shift_mm, 0.0);
}

TEST(CaseImport, BadLandmarksAndMeshesAreReportedInWords) {
  const ValveCase& truth = valve().valve_case;
  const ImportLandmarks good = landmarksOf(truth.mesh);
  const auto error = [&](const ImportLandmarks& l, const Eigen::MatrixXd& curve) {
    return importValveCase(truth.mesh.V, truth.mesh.F, l, curve, "bad").error;
  };
  ImportLandmarks far = good;
  far.anterolateral.z() += 20.0;  // 20 mm above the atrial side of the annulus
  EXPECT_NE(error(far, {}).find("anterolateral commissure landmark is "), std::string::npos)
      << error(far, {});
  EXPECT_NE(error(far, {}).find(" mm from the nearest boundary loop (at most 5.00 mm)"),
            std::string::npos)
      << error(far, {});
  ImportLandmarks at_commissure = good;
  at_commissure.anterior = good.posteromedial;
  EXPECT_NE(error(at_commissure, {}).find("anterior landmark is nearest to a commissure"),
            std::string::npos);
  ImportLandmarks same = good;
  same.posteromedial = good.anterolateral;
  EXPECT_NE(error(same, {}).find("same annulus vertex"), std::string::npos);
  EXPECT_NE(error(good, truth.annulus_closed.topRows(2)).find("at least 3 points"),
            std::string::npos);
  // A closed surface (a tetrahedron) has no annulus.
  const Eigen::MatrixXd V{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const Eigen::MatrixXi F{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  EXPECT_NE(importValveCase(V, F, good, {}, "closed").error.find("no boundary loop"),
            std::string::npos);
}

// An anterior landmark at [1e308, 0, 0] used to import (exit 0) with an arbitrary anterior
// arc: its distance to the ring was computed and never checked.
TEST(CaseImport, AnAnteriorLandmarkOffTheAnnulusOrANonFiniteLandmarkIsRefused) {
  const ValveCase& truth = valve().valve_case;
  const ImportLandmarks good = landmarksOf(truth.mesh);
  const auto error = [&](const ImportLandmarks& l) {
    return importValveCase(truth.mesh.V, truth.mesh.F, l, {}, "bad").error;
  };
  ImportLandmarks near = good;
  near.anterior.z() += 8.0;  // looser than a commissure may be, but still on this annulus
  EXPECT_EQ(error(near), "");
  for (const double x : {1e308, 40.0}) {
    ImportLandmarks far = good;
    far.anterior = Eigen::Vector3d(x, 0.0, 0.0);
    EXPECT_NE(error(far).find("the anterior landmark is "), std::string::npos) << error(far);
    EXPECT_NE(error(far).find(" mm from the annulus ring (at most 10.00 mm)"), std::string::npos)
        << error(far);
  }
  // A commissure there read "is inf mm from the nearest boundary loop" (the distance's square
  // overflowed; found by spoiling the import's JSON inputs value by value).
  for (const double z : {1e308, -1e308}) {
    ImportLandmarks far = good;
    far.anterolateral.z() = z;
    EXPECT_EQ(error(far).find("inf mm"), std::string::npos) << error(far);
    EXPECT_NE(error(far).find("the anterolateral commissure landmark is 1e+308 mm from the "
                              "nearest boundary loop"),
              std::string::npos)
        << error(far);
  }
  ImportLandmarks not_finite = good;
  not_finite.posteromedial.y() = NAN;
  EXPECT_EQ(error(not_finite), "the posteromedial commissure landmark is not a finite point");
}

// Each error says which input it is about, so that import-mesh names the landmarks' point or
// the closed annulus file instead of the mesh file.
TEST(CaseImport, AnErrorNamesTheInputAndTheLandmarksAtFault) {
  const ValveCase& truth = valve().valve_case;
  const ImportLandmarks good = landmarksOf(truth.mesh);
  const auto import = [&](const ImportLandmarks& l, const Eigen::MatrixXd& curve) {
    return importValveCase(truth.mesh.V, truth.mesh.F, l, curve, "bad");
  };
  const auto expectLandmarks = [](const ImportedCase& imported, std::vector<int> at_fault) {
    EXPECT_FALSE(imported.ok());
    EXPECT_EQ(imported.error_input, ImportInput::kLandmarks) << imported.error;
    EXPECT_EQ(imported.error_landmarks, at_fault) << imported.error;
  };
  ImportLandmarks not_finite = good;
  not_finite.anterior.x() = INFINITY;
  expectLandmarks(import(not_finite, {}), {2});
  ImportLandmarks far = good;
  far.anterior.x() += 40.0;
  expectLandmarks(import(far, {}), {2});
  ImportLandmarks far_commissure = good;
  far_commissure.posteromedial.z() += 20.0;
  expectLandmarks(import(far_commissure, {}), {1});
  ImportLandmarks same = good;
  same.posteromedial = good.anterolateral;
  expectLandmarks(import(same, {}), {0, 1});

  const ImportedCase short_curve = import(good, truth.annulus_closed.topRows(2));
  EXPECT_EQ(short_curve.error_input, ImportInput::kClosedAnnulus) << short_curve.error;
  const Eigen::MatrixXd V{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const Eigen::MatrixXi F{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  EXPECT_EQ(importValveCase(V, F, good, {}, "closed").error_input, ImportInput::kMesh);
  // An unchecked mesh with a face index past its vertices is refused, not walked.
  Eigen::MatrixXi past = truth.mesh.F;
  past(3, 2) = static_cast<int>(truth.mesh.V.rows());
  const ImportedCase refused = importValveCase(truth.mesh.V, past, good, {}, "past");
  EXPECT_EQ(refused.error_input, ImportInput::kMesh);
  EXPECT_NE(refused.error.find("out of range"), std::string::npos) << refused.error;
}

// The parametric valve's mesh and landmarks as a user's files in `dir`: valve.ply and
// landmarks.json; returns the landmarks (one per row: AL, PM, anterior).
Eigen::MatrixXd writeImportInputs(const fs::path& dir) {
  const ValveCase& truth = valve().valve_case;
  writePly(dir / "valve.ply", truth.mesh.V, truth.mesh.F);
  const ImportLandmarks l = landmarksOf(truth.mesh);
  Eigen::MatrixXd points(3, 3);
  points << l.anterolateral.transpose(), l.posteromedial.transpose(), l.anterior.transpose();
  writePointList(dir / "landmarks.json", points);
  return points;
}

TEST(ImportMeshCli, WritesALoadableCaseOrNothing) {
  TempDir dir;
  const ValveCase& truth = valve().valve_case;
  const Eigen::MatrixXd points = writeImportInputs(dir.path());
  writePointList(dir / "closed.json", truth.annulus_closed, true);

  // Tracings in their own folder, one of them in a curve file beside them.
  fs::create_directories(dir / "echo");
  testing::writeText(dir / "echo" / "p.csv", "x,y,z\n-10,0,-4\n-8,0,-6\n");
  testing::writeText(dir / "echo" / "tracings.json",
                     R"({"tracings": [
      {"plane": {"origin": [0, 0, 0], "normal": [0, 1, 0]}, "leaflet": "anterior",
       "points": [[10, 0, -4], [8, 0, -6], [6, 0, -7]]},
      {"plane": {"origin": [0, 0, 0], "normal": [0, 1, 0]}, "leaflet": "posterior",
       "file": "p.csv"}]})");
  writePointList(dir / "tips.json", Eigen::MatrixXd{{2, 12, -18}, {2, -12, -18}});

  const auto case_dir = dir / "case";
  auto r = runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                       quoted(dir / "landmarks.json") + " --closed-annulus " +
                       quoted(dir / "closed.json") + " --tracings " +
                       quoted(dir / "echo" / "tracings.json") + " --pm-tips " +
                       quoted(dir / "tips.json") + " --out " + quoted(case_dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("anterior arc: 3"), std::string::npos) << r.out;
  Diagnostics diagnostics;
  const auto loaded = loadCase(case_dir, diagnostics);
  ASSERT_TRUE(loaded);
  EXPECT_EQ(loaded->name, "case");
  EXPECT_GE(labelAgreement(loaded->mesh.leaflet, truth.mesh.leaflet), kMinLabelAgreement);
  ASSERT_EQ(loaded->tracings.size(), 2u);
  EXPECT_EQ(loaded->tracings[1].leaflet, 1);
  EXPECT_EQ(loaded->tracings[1].points.rows(), 2);
  ASSERT_TRUE(loaded->tips);
  ASSERT_EQ(loaded->tips->size(), 2u);
  EXPECT_EQ((*loaded->tips)[0].name, "anterolateral");
  EXPECT_EQ((*loaded->tips)[1].position, Eigen::Vector3d(2, -12, -18));
  EXPECT_EQ(runChordfit("validate " + quoted(case_dir)).exit_code, 0);

  writePointList(dir / "two.json", points.topRows(2));
  r = runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                  quoted(dir / "two.json") + " --out " + quoted(dir / "other"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("expected 3 points"), std::string::npos) << r.err;
  r = runChordfit("import-mesh " + quoted(dir / "missing.ply") + " --landmarks " +
                  quoted(dir / "landmarks.json") + " --out " + quoted(dir / "other"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing.ply"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "other"));
}

// A mesh written with each triangle's own three corners (as many exporters write it) is
// welded and imported as the same valve; its landmarks were blamed before ("24 mm from the
// nearest boundary loop").
TEST(ImportMeshCli, WeldsAMeshThatRepeatsEveryTrianglesCorners) {
  TempDir dir;
  const ValveCase& truth = valve().valve_case;
  writeImportInputs(dir.path());
  Eigen::MatrixXd V(3 * truth.mesh.F.rows(), 3);
  Eigen::MatrixXi F(truth.mesh.F.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      V.row(3 * f + k) = truth.mesh.V.row(truth.mesh.F(f, k));
      F(f, k) = static_cast<int>(3 * f + k);
    }
  writePly(dir / "soup.ply", V, F);
  const auto r = runChordfit("import-mesh " + quoted(dir / "soup.ply") + " --landmarks " +
                             quoted(dir / "landmarks.json") + " --out " + quoted(dir / "case"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const long welded = V.rows() - truth.mesh.V.rows();
  EXPECT_NE(r.err.find(std::to_string(welded) + " vertices merged into others at the same " +
                       "position, " + std::to_string(truth.mesh.V.rows()) + " vertices left"),
            std::string::npos)
      << r.err;
  Diagnostics diagnostics;
  const auto loaded = loadCase(dir / "case", diagnostics);
  ASSERT_TRUE(loaded);
  EXPECT_EQ(loaded->mesh.V.rows(), truth.mesh.V.rows());
  EXPECT_EQ(loaded->mesh.F.rows(), truth.mesh.F.rows());
  EXPECT_EQ(loaded->mesh.annulus.size(), truth.mesh.annulus.size());

  // --keep-seams leaves the triangles apart: every triangle's rim is a boundary loop, so no
  // loop passes near both commissures and the import is refused, nothing welded.
  const auto kept =
      runChordfit("import-mesh " + quoted(dir / "soup.ply") + " --landmarks " +
                  quoted(dir / "landmarks.json") + " --keep-seams --out " + quoted(dir / "kept"));
  EXPECT_EQ(kept.exit_code, 2) << kept.out;
  EXPECT_EQ(kept.err.find("merged into others"), std::string::npos) << kept.err;
  EXPECT_FALSE(fs::exists(dir / "kept"));
}

// import-mesh used to refuse any directory that was not empty, its own earlier output too.
// Now it publishes as every command does: an earlier run's files it no longer writes go, a
// file the user put there stays, and one of the user's that the case would replace (the
// mesh kept as open.ply beside it) is refused, leaving everything as it was.
TEST(ImportMeshCli, ReplacesAnEarlierImportKeepsTheUsersFilesAndRefusesToReplaceOne) {
  TempDir dir;
  writeImportInputs(dir.path());
  writePointList(dir / "tips.json", Eigen::MatrixXd{{2, 12, -18}, {2, -12, -18}});
  const std::string inputs =
      quoted(dir / "valve.ply") + " --landmarks " + quoted(dir / "landmarks.json");
  const fs::path case_dir = dir / "case";
  auto r = runChordfit("import-mesh " + inputs + " --pm-tips " + quoted(dir / "tips.json") +
                       " --out " + quoted(case_dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(case_dir / "pm_tips.json"));
  testing::writeText(case_dir / "notes.txt", "the user's");

  r = runChordfit("import-mesh " + inputs + " --out " + quoted(case_dir));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("wrote " + (case_dir / "case.json").string()), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("; removed pm_tips.json (an earlier run's)"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(case_dir / "pm_tips.json"));
  EXPECT_EQ(testing::readText(case_dir / "notes.txt"), "the user's");
  EXPECT_EQ(runChordfit("validate " + quoted(case_dir)).exit_code, 0);

  const fs::path mine = dir / "mine";
  fs::create_directories(mine);
  fs::copy_file(dir / "valve.ply", mine / "open.ply");
  const std::string mesh_bytes = testing::readText(mine / "open.ply");
  // The mesh itself as DIR/open.ply is an input of the run: refused before any work.
  r = runChordfit("import-mesh " + quoted(mine / "open.ply") + " --landmarks " +
                  quoted(dir / "landmarks.json") + " --out " + quoted(mine));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("error: import-mesh: --out: " + (mine / "open.ply").string() +
                       ": is an input of this run; import-mesh would write over it"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(testing::readText(mine / "open.ply"), mesh_bytes);
  // Another file of the user's where the case goes: refused when the case is written.
  r = runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                  quoted(dir / "landmarks.json") + " --out " + quoted(mine));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("error: import-mesh: --out: " + (mine / "open.ply").string() +
                       ": exists and was not written by chordfit; import-mesh does not replace "
                       "it"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(testing::readText(mine / "open.ply"), mesh_bytes);
  EXPECT_EQ(std::distance(fs::directory_iterator(mine), fs::directory_iterator()), 1)
      << "nothing else written, no staging directory left";
}

// Landmark problems used to be reported under the mesh file's name; they are the --landmarks
// file's, at the point that is wrong, and a closed-annulus problem is that file's.
TEST(ImportMeshCli, NamesTheLandmarkPointOrTheClosedAnnulusFileAtFault) {
  TempDir dir;
  const Eigen::MatrixXd points = writeImportInputs(dir.path());
  const auto import = [&](const fs::path& landmarks, const std::string& more) {
    return runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                       quoted(landmarks) + more + " --out " + quoted(dir / "case"));
  };
  Eigen::MatrixXd far = points;
  far(2, 0) += 40.0;
  writePointList(dir / "far.json", far);
  auto r = import(dir / "far.json", "");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(
      r.err.find("error: " + (dir / "far.json").string() + ": point 3: the anterior landmark is "),
      std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(" mm from the annulus ring (at most 10.00 mm)"), std::string::npos) << r.err;
  Eigen::MatrixXd far_commissure = points;
  far_commissure(1, 2) += 20.0;
  writePointList(dir / "far_commissure.json", far_commissure);
  r = import(dir / "far_commissure.json", "");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: " + (dir / "far_commissure.json").string() +
                       ": point 2: the posteromedial commissure landmark is "),
            std::string::npos)
      << r.err;
  writePointList(dir / "closed.json", valve().valve_case.annulus_closed.topRows(2), true);
  r = import(dir / "landmarks.json", " --closed-annulus " + quoted(dir / "closed.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: " + (dir / "closed.json").string() +
                       ": the closed annulus curve needs at least 3 points"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("valve.ply"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "case"));
}

// Problems the read-back of the staged case finds used to name its files (annulus_closed.json,
// pm_tips.json), which the user never saw, with the closed annulus's rows after resampling:
// they name the --closed-annulus and --pm-tips files, the points counted from 1 in the file.
TEST(ImportMeshCli, NamesTheUsersFileForAProblemOfTheStagedCase) {
  TempDir dir;
  writeImportInputs(dir.path());
  const auto import = [&](const std::string& more) {
    return runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                       quoted(dir / "landmarks.json") + more + " --out " + quoted(dir / "case"));
  };
  const Eigen::MatrixXd closed = valve().valve_case.annulus_closed;
  // The 6th point of the user's curve far above the valve: named as point 6 of that file.
  Eigen::MatrixXd one_far = closed;
  one_far(5, 2) += 150.0;
  writePointList(dir / "one_far.json", one_far, true);
  auto r = import(" --closed-annulus " + quoted(dir / "one_far.json"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("error: " + (dir / "one_far.json").string() + ": point 6: ("),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(" mm from the valve mesh"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("annulus_closed.json"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("point 1:"), std::string::npos) << "only the user's point 6: " << r.err;
  // A collapsed annulus: a problem of the whole curve, found after resampling.
  const Eigen::RowVector3d centre = closed.colwise().mean();
  const Eigen::MatrixXd collapsed = (0.1 * (closed.rowwise() - centre)).rowwise() + centre;
  writePointList(dir / "collapsed.json", collapsed, true);
  r = import(" --closed-annulus " + quoted(dir / "collapsed.json"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("error: " + (dir / "collapsed.json").string() +
                       ": after resampling onto the annulus ring: the closed annulus is "),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("annulus_closed.json"), std::string::npos) << r.err;
  // A PM tip above the annulus: point 2 of the --pm-tips file, not pm_tips.json's tips[1].
  writePointList(dir / "tips.json", Eigen::MatrixXd{{2, 12, -18}, {2, -12, 30}});
  r = import(" --pm-tips " + quoted(dir / "tips.json"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("error: " + (dir / "tips.json").string() + ": point 2: "), std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("pm_tips.json"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "case"));
}

// The import walked the mesh's boundary before any check of its faces: a face index past the
// vertices (one flipped byte of a binary PLY) crashed it. The mesh is now checked as a case's
// loader checks it first; a stray vertex is refused there too, before it becomes a case.
TEST(ImportMeshCli, ChecksTheMeshBeforeDerivingTheCaseFromIt) {
  TempDir dir;
  writeImportInputs(dir.path());
  const ValveCase& truth = valve().valve_case;
  const auto import = [&](const char* mesh) {
    return runChordfit("import-mesh " + quoted(dir / mesh) + " --landmarks " +
                       quoted(dir / "landmarks.json") + " --out " + quoted(dir / "case"));
  };
  Eigen::MatrixXi past = truth.mesh.F;
  past(7, 1) = 1 << 24;
  writePly(dir / "past.ply", truth.mesh.V, past);
  auto r = import("past.ply");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("past.ply: face 7: vertex index 16777216 out of range (mesh has " +
                       std::to_string(truth.mesh.V.rows()) + " vertices)"),
            std::string::npos)
      << r.err;
  Eigen::MatrixXd stray(truth.mesh.V.rows() + 1, 3);
  stray << truth.mesh.V, Eigen::RowVector3d(0, 0, -5);
  writePly(dir / "stray.ply", stray, truth.mesh.F);
  r = import("stray.ply");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("stray.ply: vertices[" + std::to_string(truth.mesh.V.rows()) +
                       "]: vertex in no triangle"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "case"));
}

// Corrupted copies of a good mesh (bytes after the header replaced, as a bad transfer does):
// each import ends with a case or a refusal in words (exit 0 or 2; no case left on a refusal),
// never a crash. 36 of 500 such copies crashed import-mesh before its mesh check.
TEST(ImportMeshCli, CorruptedMeshesAreImportedOrRefusedNeverACrash) {
  TempDir dir;
  writeImportInputs(dir.path());
  const std::string bytes = testing::readText(dir / "valve.ply");
  const std::size_t body = bytes.find("end_header\n") + 11;
  std::mt19937 rng(20261128);
  int refused = 0;
  constexpr int kTrials = 40;
  for (int trial = 0; trial < kTrials; ++trial) {
    std::string corrupt = bytes;
    for (int flip = 0; flip < 4; ++flip)
      corrupt[body + rng() % (corrupt.size() - body)] = static_cast<char>(rng() & 0xff);
    testing::writeText(dir / "corrupt.ply", corrupt);
    const auto case_dir = dir / ("case" + std::to_string(trial));
    const auto r = runChordfit("import-mesh " + quoted(dir / "corrupt.ply") + " --landmarks " +
                               quoted(dir / "landmarks.json") + " --out " + quoted(case_dir));
    ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 2) << "trial " << trial << ": " << r.err;
    if (r.exit_code == 2) {
      ++refused;
      EXPECT_NE(r.err.find("error: "), std::string::npos) << r.err;
      EXPECT_FALSE(fs::exists(case_dir)) << "trial " << trial;
    }
  }
  EXPECT_GT(refused, 0);  // the corruption reaches the checks, not only harmless bytes
}

// A name with a control character was refused only when the staged case was read back, as
// case.json's; it is --name's, as make-valve's is (the same check).
TEST(ImportMeshCli, RefusesANameWithAControlCharacterOrABlankOneAsItsOption) {
  TempDir dir;
  writeImportInputs(dir.path());
  for (const auto& [name, message] : std::vector<std::pair<std::string, std::string>>{
           {"\"$(printf 'a\\tb')\"",
            "error: import-mesh: --name: contains a control character (a newline, tab or NUL): "
            "give a name of printable characters\n"},
           {"'  '", "error: import-mesh: --name: is blank: give the case a name"}}) {
    const auto r = runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                               quoted(dir / "landmarks.json") + " --name " + name + " --out " +
                               quoted(dir / "case"));
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.out;
    EXPECT_NE(r.err.find(message), std::string::npos) << name << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir / "case")) << name;
  }
}

// Without --name the case is named after its directory; a blank directory name was refused only
// when the staged case was read back ("case.json: name: is blank"), a name the user never gave.
TEST(ImportMeshCli, RefusesABlankDirectoryNameAsTheDefaultNameUpFront) {
  TempDir dir;
  writeImportInputs(dir.path());
  const auto r = runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                             quoted(dir / "landmarks.json") + " --out " + quoted(dir / "  "));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("': without --name the case is named after this directory, whose name is "
                       "blank; give --name"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("case.json"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "  "));
}

// The case's default name is its directory's, also when --out ends with a slash (it was "").
TEST(ImportMeshCli, NamesTheCaseAfterItsDirectoryWithATrailingSlash) {
  TempDir dir;
  writeImportInputs(dir.path());
  const auto r = runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                             quoted(dir / "landmarks.json") + " --out " +
                             quoted(fs::path(dir.path().string() + "/mine/")));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Diagnostics diagnostics;
  const auto loaded = loadCase(dir / "mine", diagnostics);
  ASSERT_TRUE(loaded);
  EXPECT_EQ(loaded->name, "mine");
}

// Landmarks in another order or PM tips swapped used to give a case with the wrong leaflets or
// muscles and exit 0 (a warning, nothing for the tips): refused with what to change. An
// anterior point on the posterior annulus gets a warning naming it.
TEST(ImportMeshCli, RefusesLandmarksOrTipsInAnotherOrderSayingWhichOrderFits) {
  TempDir dir;
  const Eigen::MatrixXd points = writeImportInputs(dir.path());
  const auto import = [&](const fs::path& landmarks, const std::string& more) {
    return runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                       quoted(landmarks) + more + " --out " + quoted(dir / "case"));
  };
  Eigen::MatrixXd anterior_first(3, 3);
  anterior_first << points.row(2), points.row(0), points.row(1);
  writePointList(dir / "anterior_first.json", anterior_first);
  auto r = import(dir / "anterior_first.json", "");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("with point 1 as the anterior point it is 3"), std::string::npos) << r.err;

  // The posterior annulus vertex opposite the anterior landmark (farthest toward -x).
  const ValveMesh& mesh = valve().valve_case.mesh;
  Eigen::Vector3d posterior = Eigen::Vector3d::Constant(1e9);
  for (Eigen::Index k = 0; k < mesh.annulus.size(); ++k)
    if (mesh.leaflet(mesh.annulus(k)) == 1 && mesh.V(mesh.annulus(k), 0) < posterior.x())
      posterior = mesh.V.row(mesh.annulus(k));
  Eigen::MatrixXd posterior_point = points;
  posterior_point.row(2) = posterior.transpose();
  writePointList(dir / "posterior_point.json", posterior_point);
  // An anterior point on the posterior annulus reads as the other arc; so would a misplaced
  // commissure: a warning that names both, not a refusal.
  r = import(dir / "posterior_point.json", "");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("point 3 may lie on the posterior annulus, or a commissure be misplaced"),
            std::string::npos)
      << r.err;
  fs::remove_all(dir / "case");

  writePointList(dir / "swapped_tips.json", Eigen::MatrixXd{{2, -12, -18}, {2, 12, -18}});
  r = import(dir / "landmarks.json", " --pm-tips " + quoted(dir / "swapped_tips.json"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("point 1 (the anterolateral tip) lies 23.9 mm farther to the "
                       "posteromedial side than point 2 (the posteromedial tip): are they "
                       "swapped?"),
            std::string::npos)
      << r.err;
  writePointList(dir / "same_tips.json", Eigen::MatrixXd{{2, 12, -18}, {2, 12.5, -18}});
  r = import(dir / "landmarks.json", " --pm-tips " + quoted(dir / "same_tips.json"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("points 1 and 2 are less than 1 mm apart"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "case"));
}

// A valve surface has two boundary loops, the annulus and the free edge; a third is a hole
// (a triangle lost in the segmentation), whose edge would be simulated as free.
TEST(CaseImport, CountsHolesBesidesTheAnnulusAndTheFreeEdge) {
  const ValveCase& truth = valve().valve_case;
  const ImportedCase whole = importValveCase(truth.mesh.V, truth.mesh.F, landmarksOf(truth.mesh),
                                             Eigen::MatrixXd(), "whole");
  ASSERT_TRUE(whole.ok()) << whole.error;
  EXPECT_EQ(whole.holes, 0);
  // Drop a triangle none of whose vertices is on a boundary: it leaves a hole of three edges.
  std::vector<bool> on_boundary(truth.mesh.V.rows(), false);
  for (const auto& loop : boundaryLoops(truth.mesh.F))
    for (int v : loop) on_boundary[v] = true;
  Eigen::Index dropped = -1;
  for (Eigen::Index f = 0; f < truth.mesh.F.rows() && dropped < 0; ++f)
    if (!on_boundary[truth.mesh.F(f, 0)] && !on_boundary[truth.mesh.F(f, 1)] &&
        !on_boundary[truth.mesh.F(f, 2)])
      dropped = f;
  ASSERT_GE(dropped, 0);
  Eigen::MatrixXi F(truth.mesh.F.rows() - 1, 3);
  F << truth.mesh.F.topRows(dropped), truth.mesh.F.bottomRows(truth.mesh.F.rows() - dropped - 1);
  const ImportedCase holed =
      importValveCase(truth.mesh.V, F, landmarksOf(truth.mesh), Eigen::MatrixXd(), "holed");
  ASSERT_TRUE(holed.ok()) << holed.error;
  EXPECT_EQ(holed.holes, 1);
}

// Tracings whose leaflet labels disagree with the labels the landmarks gave (as when landmarks
// in RAS are read as LPS on a valve centred at the origin, where every distance check passes)
// get a warning; agreeing ones do not.
TEST(ImportMeshCli, WarnsWhenTheTracingsLieNearerTheOtherLeaflet) {
  TempDir dir;
  writeImportInputs(dir.path());
  const auto import = [&](const char* near_plus_x, const char* near_minus_x) {
    testing::writeText(dir / "tracings.json", std::string(R"({"tracings": [
      {"plane": {"origin": [0, 0, 0], "normal": [0, 1, 0]}, "leaflet": ")") +
                                                  near_plus_x + R"(",
       "points": [[12, 0, -3], [10, 0, -5], [8, 0, -7]]},
      {"plane": {"origin": [0, 0, 0], "normal": [0, 1, 0]}, "leaflet": ")" +
                                                  near_minus_x + R"(",
       "points": [[-12, 0, -3], [-10, 0, -5], [-8, 0, -7]]}]})");
    return runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                       quoted(dir / "landmarks.json") + " --tracings " +
                       quoted(dir / "tracings.json") + " --out " + quoted(dir / "case"));
  };
  auto r = import("anterior", "posterior");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("tracing points nearest to their own leaflet (open state): 100 %"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.err.find("warning:"), std::string::npos) << r.err;
  r = import("posterior", "anterior");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("tracing points nearest to their own leaflet (open state): 0 %"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.err.find("warning: most tracing points are nearer the other leaflet"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace chordfit
