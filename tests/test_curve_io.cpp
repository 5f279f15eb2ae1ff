// Curve readers: 3D Slicer markups JSON, plain point lists and delimited text.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "core/curve_io.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;

class CurveIoTest : public ::testing::Test {
 protected:
  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path path = dir_ / name;
    std::ofstream(path) << text;
    return path;
  }

  Curve readOk(const fs::path& path, int markup_index = 0) const {
    Diagnostics diagnostics;
    Curve curve;
    const bool ok = readCurve(path, curve, diagnostics, path.filename().string(), markup_index);
    std::ostringstream messages;
    diagnostics.print(messages);
    EXPECT_TRUE(ok) << messages.str();
    return curve;
  }

  // Expects failure with exactly one problem, reported against `display`.
  Problem readFails(const fs::path& path, const std::string& display = "curve.json") const {
    Diagnostics diagnostics;
    Curve curve;
    EXPECT_FALSE(readCurve(path, curve, diagnostics, display));
    EXPECT_EQ(diagnostics.problems().size(), 1u);
    if (diagnostics.problems().empty()) return {};
    EXPECT_EQ(diagnostics.problems()[0].file, display);
    return diagnostics.problems()[0];
  }

  testing::TempDir temp_;
  const fs::path dir_ = temp_.path();
};

const char* kSchema =
    "\"@schema\": \"https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/"
    "Markups/Resources/Schema/markups-schema-v1.0.3.json#\"";

// A Slicer markups file with one markup; `system` is spliced in verbatim (may be empty).
std::string markupsFile(const std::string& type, const std::string& system,
                        const std::string& control_points) {
  return std::string("{") + kSchema + ",\n\"markups\": [{\"type\": \"" + type + "\"," + system +
         "\n\"controlPoints\": [" + control_points + "]}]}\n";
}

const char* kThreePoints =
    "{\"id\": \"1\", \"label\": \"A-1\", \"position\": [1.5, -2.0, 3.25], "
    "\"positionStatus\": \"defined\"},\n"
    "{\"id\": \"2\", \"label\": \"A-2\", \"position\": [-4.0, 5.0, 6.0]},\n"
    "{\"id\": \"3\", \"label\": \"A-3\", \"position\": [7.0, 8.0, -9.5]}";

Eigen::MatrixXd threePointsLps() {
  return Eigen::MatrixXd{{1.5, -2.0, 3.25}, {-4.0, 5.0, 6.0}, {7.0, 8.0, -9.5}};
}

TEST_F(CurveIoTest, SlicerClosedCurveInLpsIsReadUnchanged) {
  const Curve c =
      readOk(write("annulus.mrk.json",
                   markupsFile("ClosedCurve", "\"coordinateSystem\": \"LPS\",", kThreePoints)));
  EXPECT_TRUE(c.closed);
  EXPECT_EQ(c.points, threePointsLps());
}

TEST_F(CurveIoTest, SlicerClosedCurveInRasHasXAndYNegated) {
  const Curve c =
      readOk(write("annulus.mrk.json",
                   markupsFile("ClosedCurve", "\"coordinateSystem\": \"RAS\",", kThreePoints)));
  Eigen::MatrixXd expected = threePointsLps();
  expected.col(0) *= -1.0;
  expected.col(1) *= -1.0;
  EXPECT_TRUE(c.closed);
  EXPECT_EQ(c.points, expected);
}

TEST_F(CurveIoTest, MissingCoordinateSystemMeansLpsAsInSlicer) {
  const Curve c = readOk(write("curve.mrk.json", markupsFile("Curve", "", kThreePoints)));
  EXPECT_FALSE(c.closed);
  EXPECT_EQ(c.points, threePointsLps());
}

TEST_F(CurveIoTest, MarkupIndexPicksOneOfSeveralMarkupsAndUndefinedPointsAreSkipped) {
  const std::string text =
      std::string("{") + kSchema +
      ", \"markups\": ["
      "{\"type\": \"Fiducial\", \"coordinateSystem\": \"LPS\", \"controlPoints\": "
      "[{\"position\": [0, 0, 0]}]},"
      "{\"type\": \"Curve\", \"coordinateSystem\": \"LPS\", \"coordinateUnits\": \"mm\", "
      "\"controlPoints\": [{\"position\": [1, 2, 3]}, "
      "{\"position\": [0, 0, 0], \"positionStatus\": \"undefined\"}, "
      "{\"position\": [4, 5, 6]}]}]}";
  const Curve c = readOk(write("two.mrk.json", text), 1);
  EXPECT_FALSE(c.closed);
  EXPECT_EQ(c.points, (Eigen::MatrixXd{{1, 2, 3}, {4, 5, 6}}));
}

TEST_F(CurveIoTest, PlainListObjectAndBareArrayAreRead) {
  const Curve closed =
      readOk(write("ring.json", "{\"points\": [[1, 2, 3], [4, 5, 6.5]], \"closed\": true}"));
  EXPECT_TRUE(closed.closed);
  EXPECT_EQ(closed.points, (Eigen::MatrixXd{{1, 2, 3}, {4, 5, 6.5}}));
  const Curve bare = readOk(write("bare.json", "[[1, 2, 3], [4, 5, 6.5]]"));
  EXPECT_FALSE(bare.closed);
  EXPECT_EQ(bare.points, closed.points);
}

TEST_F(CurveIoTest, WritePointListReadsBackBitExact) {
  const Eigen::MatrixXd points{{0.1, 1.0 / 3.0, -2.5e-300}, {1e300, -0.0, 123456.789012345678}};
  const fs::path path = dir_ / "out" / "points.json";
  writePointList(path, points, true);
  const Curve c = readOk(path);
  EXPECT_TRUE(c.closed);
  EXPECT_EQ(c.points, points);
}

TEST_F(CurveIoTest, WritePointListRefusesNonFinitePoints) {
  Eigen::MatrixXd points{{0.0, std::nan(""), 0.0}};
  EXPECT_THROW(writePointList(dir_ / "nan.json", points), std::invalid_argument);
}

TEST_F(CurveIoTest, WrongTypesAreReportedWithTheirFieldPath) {
  const std::string short_position = std::string(kThreePoints) + ",\n{\"position\": [1, 2]}";
  struct Case {
    std::string text;
    std::string where;
    std::string what_contains;
  };
  const Case cases[] = {
      {markupsFile("Curve", "", short_position), "markups[0].controlPoints[3].position",
       "expected an array of 3 numbers"},
      {markupsFile("Curve", "", "{\"position\": [1, \"2\", 3]}"),
       "markups[0].controlPoints[0].position[1]", "expected a number, got string"},
      {markupsFile("Curve", "", "{\"label\": \"no position\"}"),
       "markups[0].controlPoints[0].position", "missing"},
      {markupsFile("Curve", "\"coordinateSystem\": \"XYZ\",", kThreePoints),
       "markups[0].coordinateSystem", "\"LPS\" or \"RAS\""},
      {markupsFile("Curve", "\"coordinateUnits\": \"um\",", kThreePoints),
       "markups[0].coordinateUnits", "\"mm\""},
      {markupsFile("Curve",
                   "\"coordinateUnits\": {\"CodeValue\": \"um\", \"CodingSchemeDesignator\": "
                   "\"UCUM\"},",
                   kThreePoints),
       "markups[0].coordinateUnits.CodeValue", "\"mm\""},
      {markupsFile("Plane", "", kThreePoints), "markups[0].type", "\"Plane\""},
      {markupsFile("Curve", "", ""), "markups[0].controlPoints", "no placed control points"},
      {"{\"markups\": {}}", "markups", "expected an array"},
      {"{\"points\": [[1, 2, 3]], \"closed\": \"yes\"}", "closed", "expected true or false"},
      {"{\"points\": [[1, 2, 3], [4, 5]]}", "points[1]", "expected an array of 3 numbers"},
      {"{\"curve\": []}", "points", "missing"},
      {"[]", "(top level)", "no points"},
      {"[[1, 2, 3], 4]", "[1]", "expected an array of 3 numbers"},
  };
  for (const Case& c : cases) {
    const Problem p = readFails(write("curve.json", c.text));
    EXPECT_EQ(p.where, c.where) << c.text;
    EXPECT_NE(p.what.find(c.what_contains), std::string::npos) << p.what << "\n" << c.text;
  }
}

TEST_F(CurveIoTest, MarkupIndexOutOfRangeIsReported) {
  Diagnostics diagnostics;
  Curve curve;
  EXPECT_FALSE(readCurve(write("one.mrk.json", markupsFile("Curve", "", kThreePoints)), curve,
                         diagnostics, "one.mrk.json", 2));
  ASSERT_EQ(diagnostics.problems().size(), 1u);
  EXPECT_EQ(diagnostics.problems()[0].where, "markups");
}

TEST_F(CurveIoTest, MalformedJsonIsReportedWithLineAndColumn) {
  const Problem p = readFails(write("broken.json", "{\n  \"points\": [\n    [1, 2, 3],,\n]}"));
  EXPECT_EQ(p.where, "line 3, column 15");  // the second comma
  EXPECT_FALSE(p.what.empty());
}

TEST_F(CurveIoTest, MissingFileIsReportedAsNotFound) {
  const Problem p = readFails(dir_ / "absent.json", "annulus.mrk.json");
  EXPECT_EQ(p.what, "file not found");
}

// ---------------------------------------------------------------------------------------
// Delimited text (core/curve_csv.h): Slicer's legacy .fcsv and plain CSV / text lists.
// ---------------------------------------------------------------------------------------

TEST_F(CurveIoTest, SlicerFcsvInLpsIsReadFromItsNamedColumns) {
  const Curve c = readOk(write("tracing.fcsv",
                               "# Markups fiducial file version = 4.13\n"
                               "# CoordinateSystem = LPS\n"
                               "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,"
                               "associatedNodeID\n"
                               "0,1.5,-2,3.25,0,0,0,1,1,1,0,F-1,,\n"
                               "1,-4,5,6,0,0,0,1,1,1,0,F-2,,,2,0\n"
                               "2,7,8,-9.5,0,0,0,1,1,1,0,F-3,\"a, b\",\n"));
  EXPECT_EQ(c.points, threePointsLps());
  EXPECT_FALSE(c.closed);
}

TEST_F(CurveIoTest, SlicerFcsvInRasOrWithTheOldNumericCodeOrWithoutTheLineIsConverted) {
  for (const std::string system : {"# CoordinateSystem = RAS\n", "# CoordinateSystem = 0\n", ""}) {
    const Curve c = readOk(write("ras.fcsv", "# Markups fiducial file version = 4.6\n" + system +
                                                 "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel\n"
                                                 "a,-1.5,2,3.25,0,0,0,1,1,1\n"
                                                 "b,4,-5,6,0,0,0,1,1,1\n"
                                                 "c,-7,-8,-9.5,0,0,0,1,1,1\n"));
    EXPECT_EQ(c.points, threePointsLps()) << system;
  }
  const Curve lps = readOk(write("code1.fcsv", "# CoordinateSystem = 1\n0,1.5,-2,3.25\n"));
  EXPECT_EQ(lps.points.row(0), threePointsLps().row(0));
}

TEST_F(CurveIoTest, PlainCsvWithOrWithoutAHeaderAndAnySeparator) {
  EXPECT_EQ(readOk(write("plain.csv", "1.5,-2,3.25\n-4,5,6\n\n# a comment\n7,8,-9.5\n")).points,
            threePointsLps());
  EXPECT_EQ(readOk(write("spaces.txt", "1.5 -2 3.25\n-4\t5  6\n7 8 -9.5\n")).points,
            threePointsLps());
  EXPECT_EQ(readOk(write("semi.csv", "1.5;-2;3.25\n-4;5;6\n7;8;-9.5\n")).points, threePointsLps());
  // Header: the columns by name, anywhere in the row; x,y,z and l,p,s are LPS, r,a,s RAS.
  EXPECT_EQ(readOk(write("xyz.csv", "label,Z,x,y\nA,3.25,1.5,-2\nB,6,-4,5\nC,-9.5,7,8\n")).points,
            threePointsLps());
  EXPECT_EQ(readOk(write("lps.csv", "l,p,s\n1.5,-2,3.25\n-4,5,6\n7,8,-9.5\n")).points,
            threePointsLps());
  EXPECT_EQ(readOk(write("ras.csv",
                         "label,r,a,s,defined\nA,-1.5,2,3.25,1\nB,4,-5,6,1\n"
                         "C,-7,-8,-9.5,1\n"))
                .points,
            threePointsLps());
}

// A file of another extension is read as JSON; when it is not JSON, the error says so (it read
// "malformed JSON" alone for a .dat file of numbers).
TEST_F(CurveIoTest, AFileOfAnUnknownExtensionThatIsNotJsonSaysItWasReadAsJson) {
  Diagnostics diagnostics;
  Curve curve;
  EXPECT_FALSE(readCurve(write("t.dat", "1 2 3\n4 5 6\n"), curve, diagnostics, "t.dat"));
  ASSERT_EQ(diagnostics.problems().size(), 2u);
  EXPECT_NE(diagnostics.problems()[1].what.find(
                "read as JSON, its extension \".dat\" being none of the text curve formats' "
                "(.csv, .txt, .fcsv)"),
            std::string::npos);
  EXPECT_EQ(readOk(write("t.points", R"({"points": [[1, 2, 3], [4, 5, 6]]})")).points.rows(), 2);
}

TEST_F(CurveIoTest, DelimitedTextProblemsNameTheFileAndLine) {
  Problem p = readFails(write("bad.csv", "1,2,3\n4,five,6\n"), "tracing.csv");
  EXPECT_EQ(p.where, "line 2");
  EXPECT_EQ(p.what, "y is not a finite decimal number: \"five\"");
  p = readFails(write("short.csv", "1,2,3\n4,5\n"), "tracing.csv");
  EXPECT_EQ(p.where, "line 2");
  EXPECT_EQ(p.what, "expected at least 3 fields, got 2");
  p = readFails(write("nan.txt", "1 2 nan\n"), "tracing.txt");
  EXPECT_EQ(p.what, "z is not a finite decimal number: \"nan\"");
  // strtod read hexadecimal: "0x10" was 16.
  p = readFails(write("hex.csv", "1,2,3\n4,0x10,6\n"), "tracing.csv");
  EXPECT_EQ(p.what, "y is not a finite decimal number: \"0x10\"");
  EXPECT_EQ(readOk(write("signs.csv", "+1,-2,3e0\n4,5,6\n")).points(0, 0), 1.0);
  p = readFails(write("header.csv", "u,v,w\n1,2,3\n"), "tracing.csv");
  EXPECT_EQ(p.where, "line 1");
  EXPECT_NE(p.what.find("expected x,y,z, l,p,s or r,a,s"), std::string::npos) << p.what;
  p = readFails(write("system.fcsv", "# CoordinateSystem = IJK\n0,1,2,3\n"), "t.fcsv");
  EXPECT_NE(p.what.find("expected LPS, RAS, 0 or 1, got \"IJK\""), std::string::npos) << p.what;
  p = readFails(write("empty.csv", "# nothing\n\n"), "tracing.csv");
  EXPECT_EQ(p.what, "no points");
  p = readFails(dir_ / "absent.fcsv", "tracing.fcsv");
  EXPECT_EQ(p.what, "file not found");
  // Many bad lines: a few are reported, then the file is given up.
  std::string many;
  for (int i = 0; i < 50; ++i) many += "a,b,c\n";
  Diagnostics diagnostics;
  Curve curve;
  EXPECT_FALSE(readCurve(write("many.txt", "1,2,3\n" + many), curve, diagnostics, "many.txt"));
  EXPECT_LE(diagnostics.problems().size(), 5u);
}

}  // namespace
}  // namespace chordfit
