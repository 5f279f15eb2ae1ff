// Importing a bare valve mesh (core/case_import.h, chordfit import-mesh): on the parametric
// valve, whose ring, labels and closed annulus are known, the derived ones must match; bad
// landmarks and meshes are reported in words; the command writes a loadable case or nothing.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "core/case_import.h"
#include "core/case_io.h"
#include "core/curve_io.h"
#include "core/mesh_io.h"
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
  ImportLandmarks not_finite = good;
  not_finite.posteromedial.y() = NAN;
  EXPECT_EQ(error(not_finite), "the posteromedial commissure landmark is not a finite point");
}

TEST(ImportMeshCli, WritesALoadableCaseOrNothing) {
  TempDir dir;
  const ValveCase& truth = valve().valve_case;
  writePly(dir / "valve.ply", truth.mesh.V, truth.mesh.F);
  const ImportLandmarks l = landmarksOf(truth.mesh);
  Eigen::MatrixXd points(3, 3);
  points << l.anterolateral.transpose(), l.posteromedial.transpose(), l.anterior.transpose();
  writePointList(dir / "landmarks.json", points);
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

  r = runChordfit("import-mesh " + quoted(dir / "valve.ply") + " --landmarks " +
                  quoted(dir / "landmarks.json") + " --out " + quoted(case_dir));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("exists and is not empty"), std::string::npos) << r.err;

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
  for (const auto& entry : fs::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().string().find("import-tmp"), std::string::npos) << entry.path();
  }
}

}  // namespace
}  // namespace chordfit
