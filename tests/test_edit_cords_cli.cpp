// chordfit edit-cords end to end: the paper's editor on the command line (a scale multiplies
// the seed rest length; edited cords become manual; locked cords are left alone), and bad
// input.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "core/carpentier.h"
#include "core/case_io.h"
#include "core/cordset_io.h"
#include "core/metrics.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;
using testing::quoted;
using testing::runChordfit;
using testing::TempDir;

const fs::path kSmallCase = fs::path(CHORDFIT_CASES_DIR) / "small-normal";

CordSet readCords(const fs::path& path) {
  Diagnostics diagnostics;
  CordSet set;
  EXPECT_TRUE(readCordSet(path, path.filename().string(), set, diagnostics));
  return set;
}

// The Carpentier segment of each cord, as the command localises it (open-state vertex).
std::vector<std::string> cordSegments(const ValveCase& c, const CordSet& set) {
  const Eigen::VectorXi segments = openStateSegments(c.mesh);
  std::vector<std::string> names;
  for (const Cord& cord : set.cords) {
    names.push_back(segmentName(c.mesh.leaflet_names, segments(cord.vertex)));
  }
  return names;
}

TEST(EditCordsCli, ScalesTheSeedLengthMostSpecificLastMarksManualAndLocks) {
  TempDir dir;
  const auto out = dir / "manual.json";
  const auto r =
      runChordfit("edit-cords " + quoted(kSmallCase) +
                  " --all 0.9 --segment P2=1.2 --cord 0=0.8 --lock edited --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Diagnostics diagnostics;
  const auto c = loadCase(kSmallCase, diagnostics);
  ASSERT_TRUE(c && c->cords);
  const CordSet& seed = *c->cords;
  const CordSet edited = readCords(out);
  ASSERT_EQ(edited.cords.size(), seed.cords.size());
  const std::vector<std::string> segment = cordSegments(*c, seed);
  int p2 = 0;
  for (std::size_t i = 0; i < seed.cords.size(); ++i) {
    const double scale = i == 0 ? 0.8 : segment[i] == "P2" ? 1.2 : 0.9;
    p2 += (i != 0 && segment[i] == "P2") ? 1 : 0;
    const Cord& cord = edited.cords[i];
    EXPECT_DOUBLE_EQ(cord.seed_rest_length, seed.cords[i].seed_rest_length) << "cord " << i;
    EXPECT_DOUBLE_EQ(cord.rest_length, scale * seed.cords[i].seed_rest_length) << "cord " << i;
    EXPECT_EQ(cord.provenance, Provenance::kManual) << "cord " << i;
    EXPECT_TRUE(cord.locked) << "cord " << i;
  }
  EXPECT_GT(p2, 0) << "the small case has P2 cords";
  EXPECT_NE(r.out.find("edited"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" 1 cord scaled\n"), std::string::npos) << "--cord 0=0.8: " << r.out;
  for (const auto& entry : fs::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().string().find(".chordfit-tmp."), std::string::npos)
        << "left a temp file";
  }
}

// The note on scales the fit would clamp names the cords, and a scale that misses the bound
// by rounding only (seed * 0.7 reads back as 0.6999999999999998) is on the bound, as the fit
// takes it.
TEST(EditCordsCli, NotesOnlyScalesReallyOutsideTheFitsBoundsAndNamesTheirCords) {
  TempDir dir;
  auto r = runChordfit("edit-cords " + quoted(kSmallCase) + " --all 0.7 --out " +
                       quoted(dir / "on_bound.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("outside the fit's default bounds"), std::string::npos) << r.err;
  r = runChordfit("edit-cords " + quoted(kSmallCase) + " --all 0.7 --cord 3=0.6 --cord 5=1.6 " +
                  "--out " + quoted(dir / "beyond.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: 2 unlocked cords (3,5) have a scale outside the fit's default "
                       "bounds [0.7, 1.5]"),
            std::string::npos)
      << r.err;
}

TEST(EditCordsCli, LockedCordsAreLeftAloneUntilUnlocked) {
  TempDir dir;
  auto r = runChordfit("edit-cords " + quoted(kSmallCase) + " --cord 1,2=0.85 --lock 1 --out " +
                       quoted(dir / "a.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CordSet a = readCords(dir / "a.json");
  ASSERT_GT(a.cords.size(), 3u);
  EXPECT_TRUE(a.cords[1].locked);
  EXPECT_FALSE(a.cords[2].locked);

  r = runChordfit("edit-cords " + quoted(kSmallCase) + " --cords " + quoted(dir / "a.json") +
                  " --all 1.1 --out " + quoted(dir / "b.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("1 locked left alone"), std::string::npos) << r.out;
  const CordSet b = readCords(dir / "b.json");
  EXPECT_EQ(b.cords[1].rest_length, a.cords[1].rest_length) << "locked: bit for bit";
  EXPECT_TRUE(b.cords[1].locked);
  EXPECT_DOUBLE_EQ(b.cords[2].rest_length, 1.1 * a.cords[2].seed_rest_length);

  r = runChordfit("edit-cords " + quoted(kSmallCase) + " --cords " + quoted(dir / "b.json") +
                  " --unlock all --cord 1=1.05 --out " + quoted(dir / "c.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CordSet c = readCords(dir / "c.json");
  EXPECT_FALSE(c.cords[1].locked);
  EXPECT_DOUBLE_EQ(c.cords[1].rest_length, 1.05 * a.cords[1].seed_rest_length);
}

// The summary counts locks as they changed, and an edit that changes no length says what it
// did do: --all 1 makes every cord manual ("nothing changed" said it left the file as it was),
// --lock edited without an edit locks nothing, --unlock all on an unlocked set unlocks none
// (it said "32 unlocked").
TEST(EditCordsCli, SaysWhatAnEditThatChangesNoLengthDid) {
  TempDir dir;
  auto r =
      runChordfit("edit-cords " + quoted(kSmallCase) + " --all 1 --out " + quoted(dir / "a.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: edit-cords: no rest length changed (scale 1); 32 cords now "
                       "manual"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(readCords(dir / "a.json").cords[0].provenance, Provenance::kManual);

  r = runChordfit("edit-cords " + quoted(kSmallCase) + " --unlock all --lock edited --out " +
                  quoted(dir / "b.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("32 cords, 0 edited, 0 locked, 0 unlocked, 0 locked in all"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.err.find("--lock edited: no cord was edited, so none was locked"), std::string::npos)
      << r.err;

  r = runChordfit("edit-cords " + quoted(kSmallCase) + " --cord 4=1.2 --lock 4,5 --out " +
                  quoted(dir / "c.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = runChordfit("edit-cords " + quoted(kSmallCase) + " --cords " + quoted(dir / "c.json") +
                  " --unlock all --lock 5 --out " + quoted(dir / "d.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("0 edited, 0 locked, 1 unlocked, 1 locked in all"), std::string::npos)
      << r.out;
}

// A scaling refused for the rest length it gives, or a refused tip move, prints no "cords
// scaled" line for an edit that is not written.
TEST(EditCordsCli, ARefusedScalingPrintsNoScaledLine) {
  TempDir dir;
  const auto r = runChordfit("edit-cords " + quoted(kSmallCase) + " --all 0.001 --out " +
                             quoted(dir / "a.json"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("a cord set holds 1 to 1000 mm"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("scaled"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "a.json"));

  // Nor for one whose tip move is refused.
  const auto moved = runChordfit("edit-cords " + quoted(kSmallCase) +
                                 " --cord 3=0.9 --move-tip anterolateral=0,0,1000 --out " +
                                 quoted(dir / "a.json"));
  EXPECT_EQ(moved.exit_code, 2) << moved.err;
  EXPECT_NE(moved.err.find("--move-tip"), std::string::npos) << moved.err;
  EXPECT_EQ(moved.out.find("scaled"), std::string::npos) << moved.out;
  EXPECT_FALSE(fs::exists(dir / "a.json"));
}

// A segment or group typed in another case is the one it names ("p2" was "no cord in segment").
TEST(EditCordsCli, ASegmentNameInAnotherCaseIsTheSegment) {
  TempDir dir;
  ASSERT_EQ(runChordfit("edit-cords " + quoted(kSmallCase) + " --segment P2=1.1 --out " +
                        quoted(dir / "upper.json"))
                .exit_code,
            0);
  const auto r = runChordfit("edit-cords " + quoted(kSmallCase) +
                             " --segment p2=1.1 --group POSTERIOR/POSTEROMEDIAL=1 --out " +
                             quoted(dir / "lower.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CordSet upper = readCords(dir / "upper.json"), lower = readCords(dir / "lower.json");
  ASSERT_EQ(upper.cords.size(), lower.cords.size());
  for (std::size_t i = 0; i < upper.cords.size(); ++i)
    EXPECT_EQ(upper.cords[i].rest_length == upper.cords[i].seed_rest_length,
              lower.cords[i].rest_length == lower.cords[i].seed_rest_length)
        << "cord " << i;
}

TEST(EditCordsCli, MoveTipShiftsTheTipAndKeepsTheRestLengths) {
  TempDir dir;
  const auto r = runChordfit("edit-cords " + quoted(kSmallCase) +
                             " --move-tip posteromedial=1,-2,0.5 --out " + quoted(dir / "t.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Diagnostics diagnostics;
  const auto c = loadCase(kSmallCase, diagnostics);
  ASSERT_TRUE(c && c->cords);
  const CordSet moved = readCords(dir / "t.json");
  ASSERT_EQ(moved.tips.size(), c->cords->tips.size());
  for (std::size_t t = 0; t < moved.tips.size(); ++t) {
    const PmTip& before = c->cords->tips[t];
    const Eigen::Vector3d offset =
        before.name == "posteromedial" ? Eigen::Vector3d(1, -2, 0.5) : Eigen::Vector3d::Zero();
    EXPECT_TRUE(moved.tips[t].position.isApprox(before.position + offset, 1e-12)) << before.name;
    ASSERT_EQ(moved.tips[t].closed_position.has_value(), before.closed_position.has_value());
    if (before.closed_position) {
      EXPECT_TRUE(moved.tips[t].closed_position->isApprox(*before.closed_position + offset, 1e-12));
    }
  }
  for (std::size_t i = 0; i < moved.cords.size(); ++i) {
    EXPECT_EQ(moved.cords[i].rest_length, c->cords->cords[i].rest_length) << "cord " << i;
  }
}

TEST(EditCordsCli, BadInputExitsTwoNamingTheProblemAndWritesNothing) {
  TempDir dir;
  const auto out = dir / "out.json";
  CordSet long_cord = readCords(kSmallCase / "cords.json");
  long_cord.cords[0].seed_rest_length = long_cord.cords[0].rest_length = 300.0;
  writeCordSet(dir / "long.json", long_cord);
  CordSet same_names = readCords(kSmallCase / "cords.json");
  same_names.tips[1].name = same_names.tips[0].name;
  writeCordSet(dir / "same_names.json", same_names);
  CordSet no_cords = readCords(kSmallCase / "cords.json");
  no_cords.cords.clear();
  writeCordSet(dir / "no_cords.json", no_cords);
  for (const auto& [arguments, message] : std::vector<std::pair<std::string, std::string>>{
           {"", "nothing to do"},
           {"--segment P4=1.1", "--segment P4=1.1: no cord in segment \"P4\""},
           {"--segment P2=0", "--segment P2=0: the scale must be a number in (0, 10]"},
           {"--segment P2", "--segment P2: expected NAME=SCALE"},
           {"--group anterior/nowhere=1", "no cord in group \"anterior/nowhere\""},
           {"--cord 9999=1", "--cord 9999=1: \"9999\" is not a cord index"},
           {"--cord 1,1=1.1", "--cord 1,1=1.1: cord 1 appears twice in the list"},
           {"--lock ''", "--lock: empty; expected cord indices"},
           {"--all 1 --unlock ''", "--unlock: empty; expected cord indices"},
           {"--all 1 --lock 1,z", "--lock 1,z: \"z\" is not a cord index"},
           {"--all nan", "--all nan: the scale must be a number"},
           // 0.001 of a 16 mm seed: a cord set the readers refuse (at least 1 mm).
           {"--all 0.001", "cord 0: the scalings give it a rest length of 0.0"},
           {"--cords " + quoted(dir / "long.json") + " --cord 0=10",
            "cord 0: the scalings give it a rest length of 3000 mm (its seed 300 mm times 10); a "
            "cord set holds 1 to 1000 mm"},
           {"--move-tip elsewhere=1,2,3", "--move-tip elsewhere=1,2,3: expected NAME=DX,DY,DZ"},
           {"--move-tip anterolateral=1,2", "the offset must be three finite numbers"},
           {"--move-tip anterolateral=1e9,0,0", "--move-tip: tips[0].position: (1e+09, "},
           {"--all 1 --unlock edited", "--unlock edited: \"edited\" is not a cord index"},
           {"--cords " + quoted(dir / "missing.json") + " --all 1", "missing.json"},
           // The set without cords, named (it was "the cord set has no cords").
           {"--cords " + quoted(dir / "no_cords.json") + " --all 1",
            "error: edit-cords: " + (dir / "no_cords.json").string() +
                " has no cords: nothing to edit"},
           // A cord, group, segment or tip given twice: the last one silently won (scales) or
           // they added up (tip offsets).
           {"--cord 1=1.2 --cord 1=0.8",
            "--cord 1=0.8: cord 1 is already scaled by --cord 1=1.2: give each cord once"},
           {"--cord 0,1,2=1.2 --cord 2,3=0.8",
            "--cord 2,3=0.8: cord 2 is already scaled by --cord 0,1,2=1.2"},
           {"--segment P2=1.1 --segment P2=0.9",
            "--segment P2=0.9: segment \"P2\" is already scaled by --segment P2=1.1"},
           {"--group posterior/anterolateral=1.1 --group posterior/anterolateral=0.9",
            "group \"posterior/anterolateral\" is already scaled by --group "
            "posterior/anterolateral=1.1"},
           {"--move-tip anterolateral=0,0,-1 --move-tip anterolateral=0,0,-2",
            "--move-tip anterolateral=0,0,-2: tip \"anterolateral\" is already moved by --move-tip "
            "anterolateral=0,0,-1: give one offset per tip"},
           // Two tips of one name: which one --move-tip means is unknown (it moved the second).
           {"--cords " + quoted(dir / "same_names.json") + " --move-tip anterolateral=0,0,-1",
            "same_names.json: tips[1].name: \"anterolateral\" repeats tips[0].name"}}) {
    const auto r =
        runChordfit("edit-cords " + quoted(kSmallCase) + " " + arguments + " --out " + quoted(out));
    EXPECT_EQ(r.exit_code, 2) << arguments;
    EXPECT_NE(r.err.find(message), std::string::npos) << arguments << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << arguments;
  }
}

}  // namespace
}  // namespace chordfit
