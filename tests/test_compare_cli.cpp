// `chordfit compare` end to end: two cord sets on the bundled small case (each closure takes
// about a second), and the input errors that must stop it before any simulation.
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/csv_text.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;
using testing::readText;
using testing::runChordfit;
using testing::TempDir;

using testing::quoted;

std::vector<std::vector<std::string>> csvRows(const std::string& text) {
  return parseSimpleCsv(text);
}

class CompareCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    if (!fs::exists(caseDir() / "case.json")) return;  // reported by SetUp
    // A "manual" edit: every cord 40 % longer than the heuristic seed. Loose cords let the
    // leaflets billow, so this set must close differently.
    nlohmann::json cords = nlohmann::json::parse(readText(caseDir() / "cords.json"));
    for (auto& cord : cords["cords"]) {
      cord["rest_length_mm"] = 1.4 * cord["rest_length_mm"].get<double>();
      cord["scale"] = 1.4;
      cord["provenance"] = "manual";
    }
    testing::writeText(*dir_ / "loose.json", cords.dump(1));
  }
  static void TearDownTestSuite() { delete dir_; }
  void SetUp() override {
    ASSERT_TRUE(fs::exists(caseDir() / "case.json"))
        << caseDir() << ": bundled case missing (cmake --build BUILD --target cohort_cases)";
  }
  // The bundled small test case (cases/CMakeLists.txt: normal-1 seed 2, edge 3 mm, 3 planes).
  static fs::path caseDir() {
    return fs::path(CHORDFIT_EXE).parent_path().parent_path() / "cases" / "small-normal";
  }

  static TempDir* dir_;
};
TempDir* CompareCommand::dir_ = nullptr;

TEST_F(CompareCommand, TabulatesEveryCordSetInTheTable1LayoutAndWritesMarkdownAndCsv) {
  const fs::path out = *dir_ / "compare";
  const auto r =
      runChordfit("compare " + quoted(caseDir()) + " " + quoted(caseDir() / "cords.json") + " " +
                  quoted(*dir_ / "loose.json") + " --labels heuristic,loose --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| Cord set | Area (mm²) | MinD (mm) | MedD (mm) | MaxD (mm) | AvgD (mm) | "
                       "Prolapse Recon. |"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("| heuristic | "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| loose | "), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("compare: [2/2] loose"), std::string::npos) << "progress on stderr";

  const std::string md = readText(out / "compare.md");
  EXPECT_NE(md.find("| heuristic | "), std::string::npos);
  EXPECT_NE(md.find(" ± "), std::string::npos) << "AvgD ± SD";

  const auto rows = csvRows(readText(out / "compare.csv"));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"label",
                                               "cords_file",
                                               "area_mm2",
                                               "min_mm",
                                               "median_mm",
                                               "max_mm",
                                               "mean_mm",
                                               "sd_mm",
                                               "prolapse_reconstructed",
                                               "section_prolapse_segments",
                                               "prolapse_segments",
                                               "tracing_prolapse_segments",
                                               "converged",
                                               "steps",
                                               "recovery_median_pct",
                                               "recovery_median_pct_taut",
                                               "max_tip_offset_mm",
                                               "orifice_coverage",
                                               "open_orifice_area_mm2",
                                               "self_intersections"}));
  for (std::size_t r = 1; r < rows.size(); ++r) {
    ASSERT_EQ(rows[r].size(), rows[0].size()) << "row " << r;
    EXPECT_TRUE(rows[r][8] == "yes" || rows[r][8] == "no") << rows[r][8];
    EXPECT_GT(std::stoi(rows[r][13]), 0) << "steps";
    EXPECT_GT(std::stod(rows[r][17]), 0.5) << "orifice coverage";
    EXPECT_EQ(rows[r][19], "0") << "self-intersections";
    EXPECT_LE(std::stod(rows[r][3]), std::stod(rows[r][4]));  // min <= median
    EXPECT_LE(std::stod(rows[r][4]), std::stod(rows[r][5]));  // median <= max
  }
  EXPECT_EQ(rows[1][0], "\"heuristic\"");
  EXPECT_EQ(rows[2][0], "\"loose\"");
  // The loose set closes differently: a different mean deviation (the test would pass with
  // two identical rows otherwise).
  EXPECT_NE(rows[1][6], rows[2][6]);
  // Both closures against the tracings, one colour per cord set.
  const std::string svg = readText(out / "sections.svg");
  EXPECT_NE(svg.find(">heuristic<"), std::string::npos);
  EXPECT_NE(svg.find(">loose<"), std::string::npos);
  // And one atrial view per set, in the order given.
  EXPECT_NE(readText(out / "enface_1.svg").find(", heuristic: closed valve from the atrium"),
            std::string::npos);
  EXPECT_NE(readText(out / "enface_2.svg").find(", loose: closed valve from the atrium"),
            std::string::npos);
  // On one height scale and at one size: their <svg> elements and height scales read alike.
  auto scaleAndSize = [&](const char* name) {
    const std::string svg = readText(out / name);
    const std::size_t top = svg.find("\xE2\x89\xA5 ");
    return svg.substr(0, svg.find("font-family")) + svg.substr(top, svg.find('<', top) - top);
  };
  EXPECT_EQ(scaleAndSize("enface_1.svg"), scaleAndSize("enface_2.svg"));
  EXPECT_NE(readText(out / "enface_1.svg").find("(one scale for all 2 figures)"),
            std::string::npos);
}

// The bundled case is a make-case case: each set is also measured against its truth. The
// truth's own lengths and tips read 0; the heuristic's do not.
TEST_F(CompareCommand, MeasuresEachCordSetAgainstTheCasesTruth) {
  nlohmann::json cords = nlohmann::json::parse(readText(caseDir() / "cords.json"));
  const nlohmann::json truth = nlohmann::json::parse(readText(caseDir() / "truth" / "truth.json"));
  ASSERT_EQ(cords["cords"].size(), truth["cords"].size());
  for (std::size_t i = 0; i < cords["cords"].size(); ++i) {
    cords["cords"][i]["rest_length_mm"] = truth["cords"][i]["true_rest_length_mm"];
    cords["cords"][i]["provenance"] = "manual";
  }
  for (std::size_t k = 0; k < cords["tips"].size(); ++k)
    cords["tips"][k]["position"] = truth["tips"][k]["true_position"];
  const fs::path out = *dir_ / "truth-compare";
  testing::writeText(out / "true.json", cords.dump(1));
  const auto r = runChordfit("compare " + quoted(caseDir()) + " " +
                             quoted(caseDir() / "cords.json") + " " + quoted(out / "true.json") +
                             " --labels heuristic,true --quiet --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = csvRows(readText(out / "compare.csv"));
  ASSERT_EQ(rows.size(), 3u);
  ASSERT_EQ(rows[0].size(), 20u);
  EXPECT_EQ(rows[2][14], "0.000") << "the truth's lengths";
  EXPECT_EQ(rows[2][16], "0.000") << "the truth's tips";
  EXPECT_GT(std::stod(rows[1][14]), 5.0) << "the heuristic is the lengths' upper bound";
  EXPECT_NE(r.out.find("against the truth (truth/truth.json), median |rest / true - 1|: 0.0 %"),
            std::string::npos)
      << r.out;
  EXPECT_NE(readText(out / "compare.md").find("Against the case's truth"), std::string::npos);
  // The case's cords keep the heuristic's tips: their offset is said to be the heuristic's.
  EXPECT_EQ(testing::occurrences(r.out, "(the heuristic's, not moved)"), 1u) << r.out;
  // The truth's own AvgD, the noise floor, for context.
  const auto truth_metrics = nlohmann::json::parse(readText(caseDir() / "truth" / "metrics.json"));
  char floor[64];
  std::snprintf(floor, sizeof floor, "reach AvgD %.2f mm", truth_metrics["mean_mm"].get<double>());
  EXPECT_NE(r.out.find(floor), std::string::npos) << r.out;

  // Per cord and set: its length and signed error against the truth, in cords.csv and as a
  // side-by-side table in compare.md.
  const auto cord_rows = csvRows(readText(out / "cords.csv"));
  const std::size_t n = cords["cords"].size();
  ASSERT_EQ(cord_rows.size(), 1 + 2 * n);
  EXPECT_EQ(cord_rows[0][9], "error_pct");
  const nlohmann::json heuristic = nlohmann::json::parse(readText(caseDir() / "cords.json"));
  for (std::size_t i = 0; i < n; ++i) {
    const auto& h = cord_rows[1 + i];
    const auto& t = cord_rows[1 + n + i];
    EXPECT_EQ(h[1], std::to_string(i));
    const double true_length = truth["cords"][i]["true_rest_length_mm"].get<double>();
    const double heuristic_length = heuristic["cords"][i]["rest_length_mm"].get<double>();
    EXPECT_NEAR(std::stod(h[9]), 100.0 * (heuristic_length / true_length - 1.0), 1e-3) << i;
    EXPECT_EQ(t[9], "0.000") << i;
    EXPECT_EQ(t[6], "manual") << i;
  }
  const std::string md = readText(out / "compare.md");
  EXPECT_NE(md.find("| Cord | Group | Kind | True (mm) | Taut in the truth | heuristic | true |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("(+0.0 %) |\n"), std::string::npos) << md;
}

TEST_F(CompareCommand, LabelsDefaultToTheFileNames) {
  const auto r = runChordfit("compare " + quoted(caseDir()) + " " +
                             quoted(caseDir() / "cords.json") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| " + (caseDir() / "cords.json").string() + " | "), std::string::npos)
      << r.out;
  EXPECT_TRUE(r.err.empty()) << "--quiet: " << r.err;
}

// The truth is context: a truth.json with a key given twice (which one is the truth?) is set
// aside with a warning naming the key, not read with its last value.
TEST_F(CompareCommand, ATruthWithADuplicateKeyIsSetAsideNamingTheKey) {
  const fs::path case_copy = *dir_ / "duplicate-truth";
  fs::copy(caseDir(), case_copy, fs::copy_options::recursive);
  std::string truth = readText(case_copy / "truth" / "truth.json");
  truth.replace(truth.find('{'), 1, R"({"cords": [], )");
  testing::writeText(case_copy / "truth" / "truth.json", truth);
  const auto r = runChordfit("compare " + quoted(case_copy) + " " +
                             quoted(case_copy / "cords.json") + " --out " + quoted(*dir_ / "dt"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("truth.json: cords: duplicate key: given more than once in this object, "
                       "and only one of its values would be read: keep one; compared without "
                       "the truth\n"),
            std::string::npos)
      << r.err;
}

TEST_F(CompareCommand, RemovesTheFiguresOfCordSetsAnEarlierCompareHadAndKeepsOtherFiles) {
  // An earlier compare of two cord sets into the same directory left enface_2.svg; beside
  // this run's one figure it would read as its own. Files no run recorded stay.
  const fs::path out = *dir_ / "earlier-run";
  const auto earlier =
      runChordfit("compare " + quoted(caseDir()) + " " + quoted(caseDir() / "cords.json") + " " +
                  quoted(*dir_ / "loose.json") + " --quiet --out " + quoted(out));
  ASSERT_EQ(earlier.exit_code, 0) << earlier.err;
  ASSERT_TRUE(fs::exists(out / "enface_2.svg"));
  for (const char* name : {"enface_10.svg", "enface_01.svg", "notes.txt"})
    testing::writeText(out / name, "the user's");
  const auto r = runChordfit("compare " + quoted(caseDir()) + " " +
                             quoted(caseDir() / "cords.json") + " --quiet --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(out / "enface_2.svg"));
  EXPECT_TRUE(fs::exists(out / "enface_1.svg"));
  for (const char* name : {"enface_10.svg", "enface_01.svg", "notes.txt"})
    EXPECT_EQ(readText(out / name), "the user's") << name << ": no run recorded it";
  EXPECT_NE(r.out.find("wrote " + (out / "compare.md").string() +
                       ", compare.csv, cords.csv, sections.svg, enface_1.svg; removed "
                       "enface_2.svg"),
            std::string::npos)
      << r.out;
}

TEST_F(CompareCommand, RejectsALabelCountMismatchBeforeSimulating) {
  const fs::path out = *dir_ / "mismatch";
  const auto r =
      runChordfit("compare " + quoted(caseDir()) + " " + quoted(caseDir() / "cords.json") + " " +
                  quoted(*dir_ / "loose.json") + " --labels only-one --out " + quoted(out));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: compare: --labels: 1 label(s) for 2 cord file(s)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("closing"), std::string::npos) << "no simulation may start";
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CompareCommand, ADirectoryInTheWayOfTheSecondEnfaceFigureExitsWith2BeforeSimulating) {
  const fs::path out = *dir_ / "in-the-way";
  fs::create_directories(out / "enface_2.svg");
  const auto r =
      runChordfit("compare " + quoted(caseDir()) + " " + quoted(caseDir() / "cords.json") + " " +
                  quoted(*dir_ / "loose.json") + " --out " + quoted(out));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: compare: --out: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("enface_2.svg: a directory of that name is in the way"), std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("closing"), std::string::npos) << "no simulation may start";
  EXPECT_FALSE(fs::exists(out / "compare.csv"));
}

TEST_F(CompareCommand, SetAppliesToEveryClosureAndIsNamedInTheMarkdown) {
  // The row's AvgD is that of `simulate --set` with the same cords, not the case's settings'.
  const fs::path out = *dir_ / "set";
  const std::string set = " --set pressure_mmhg=90";
  const auto r =
      runChordfit("compare " + quoted(caseDir()) + " " + quoted(caseDir() / "cords.json") + set +
                  " --quiet --out " + quoted(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(readText(out / "compare.md").find("and `--set` `pressure_mmhg=90`"), std::string::npos);
  const auto csv = csvRows(readText(out / "compare.csv"));
  ASSERT_EQ(csv.size(), 2u);
  const double compared_mean = std::stod(csv[1][6]);  // mean_mm
  for (const std::string& with : {set, std::string()}) {
    const fs::path sim = *dir_ / (with.empty() ? "plain" : "sim");
    ASSERT_EQ(runChordfit("simulate " + quoted(caseDir()) + " --cords " +
                          quoted(caseDir() / "cords.json") + with + " --quiet --out " + quoted(sim))
                  .exit_code,
              0);
    const double mean =
        nlohmann::json::parse(readText(sim / "metrics.json"))["mean_mm"].get<double>();
    if (with.empty())
      EXPECT_GT(std::abs(mean - compared_mean), 1e-3) << "the case's own pressure";
    else
      EXPECT_NEAR(mean, compared_mean, 1e-4);  // the CSV's precision
  }
  const auto bad = runChordfit("compare " + quoted(caseDir()) + " " +
                               quoted(caseDir() / "cords.json") + " --set pressure_mmhg=1e9");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("compare: --set: simulation.pressure_mmhg"), std::string::npos) << bad.err;
  EXPECT_EQ(bad.err.find("closing"), std::string::npos) << "no simulation may start";
}

TEST_F(CompareCommand, RejectsDuplicateLabels) {
  const auto r =
      runChordfit("compare " + quoted(caseDir()) + " " + quoted(caseDir() / "cords.json") + " " +
                  quoted(*dir_ / "loose.json") + " --labels same,same");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("\"same\" appears twice"), std::string::npos) << r.err;
}

// Without --labels the labels are the file names: a file given twice used to be reported as
// `--labels: "c.json" appears twice`, an option the user never gave.
TEST_F(CompareCommand, AFileGivenTwiceWithoutLabelsNamesTheCordFilesNotLabels) {
  const std::string cords = quoted(caseDir() / "cords.json");
  const auto r = runChordfit("compare " + quoted(caseDir()) + " " + cords + " " + cords);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: compare: CORDS: \"" + (caseDir() / "cords.json").string() +
                       "\" is given twice (without --labels the file names label the rows; "
                       "give --labels)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("--labels:"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("closing"), std::string::npos) << "no simulation may start";
}

TEST_F(CompareCommand, RejectsAMissingCordFileWithoutWritingAnything) {
  const fs::path out = *dir_ / "missing";
  const auto r =
      runChordfit("compare " + quoted(caseDir()) + " " + quoted(caseDir() / "cords.json") + " " +
                  quoted(*dir_ / "nope.json") + " --out " + quoted(out));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nope.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("file not found"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("closing"), std::string::npos) << "checked before the first closure";
  EXPECT_FALSE(fs::exists(out / "compare.csv"));
}

// A tissue file is named with its option: "error: nope.json: file not found" did not say
// whether a cord file or a tissue file was missing.
TEST_F(CompareCommand, RejectsAMissingTissueFileNamingTheOption) {
  const fs::path out = *dir_ / "missing-tissue";
  const auto r =
      runChordfit("compare " + quoted(caseDir()) + " " + quoted(caseDir() / "cords.json") +
                  " --tissues " + quoted(*dir_ / "nope.json") + " --out " + quoted(out));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: compare: --tissues: " + (*dir_ / "nope.json").string() +
                       ": file not found"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("closing"), std::string::npos) << "checked before the first closure";
  EXPECT_FALSE(fs::exists(out / "compare.csv"));
}

TEST_F(CompareCommand, RejectsAMissingCase) {
  const auto r =
      runChordfit("compare " + quoted(*dir_ / "no-case") + " " + quoted(caseDir() / "cords.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no-case"), std::string::npos) << r.err;
}

TEST_F(CompareCommand, RejectsACordSetOfAnotherMesh) {
  // truth/cords.json belongs to the finer truth mesh: vertex indices beyond the case mesh.
  const auto r = runChordfit("compare " + quoted(caseDir()) + " " +
                             quoted(caseDir() / "truth" / "cords.json"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("truth/cords.json"), std::string::npos) << r.err;
}

TEST_F(CompareCommand, ADivergingClosureExitsWith3AndWritesNothing) {
  // Settings inside their ranges that still diverge (testing::kDivergingSimulationJson), on
  // the coarse parametric valve where they blow up fastest.
  const fs::path case_copy = *dir_ / "diverging-case";
  ASSERT_EQ(runChordfit("make-valve --edge 3.0 --out " + quoted(case_copy)).exit_code, 0);
  ASSERT_EQ(runChordfit("heuristic " + quoted(case_copy) + " --out " +
                        quoted(*dir_ / "diverging-cords.json"))
                .exit_code,
            0);
  nlohmann::json c = nlohmann::json::parse(readText(case_copy / "case.json"));
  c["simulation"] = nlohmann::json::parse(testing::kDivergingSimulationJson);
  testing::writeText(case_copy / "case.json", c.dump());
  const fs::path out = *dir_ / "diverged";
  const auto r = runChordfit(
      "compare " + quoted(case_copy) + " " + quoted(*dir_ / "diverging-cords.json") + " " +
      quoted(*dir_ / "diverging-cords.json") + " --labels a,b --out " + quoted(out));
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("simulation failed"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "compare.md"));
  EXPECT_FALSE(fs::exists(out / "compare.csv"));
}

}  // namespace
}  // namespace chordfit
