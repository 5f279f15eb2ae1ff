#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include <gtest/gtest.h>

#include "core/atomic_file.h"
#include "core/json_fields.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

TEST(ParseJson, ReportsANumberBeyondDoubleRangeAsAProblemOfTheFile) {
  Diagnostics diagnostics;
  EXPECT_FALSE(parseJson("{\"simulation\": {\"ramp_ms\": 1e999}}", "case.json", diagnostics));
  ASSERT_EQ(diagnostics.problems().size(), 1u);
  std::ostringstream printed;
  diagnostics.print(printed);
  EXPECT_NE(printed.str().find("case.json"), std::string::npos) << printed.str();
  EXPECT_NE(printed.str().find("overflow"), std::string::npos) << printed.str();
}

// A whole number written as 2000.0 (scripts that hold every number as a float) is read as the
// integer; 2000.5 and a string are refused naming the value or its type.
TEST(JsonFieldsInteger, ReadsAWholeNumberWithAFractionPartAndNamesAFraction) {
  Diagnostics diagnostics;
  JsonFields fields("case.json", diagnostics);
  int out = 0;
  EXPECT_TRUE(fields.integer(nlohmann::json::parse("2000.0"), "simulation.max_steps", out));
  EXPECT_EQ(out, 2000);
  EXPECT_TRUE(fields.integer(nlohmann::json::parse("-3"), "x", out));
  EXPECT_EQ(out, -3);
  EXPECT_FALSE(fields.integer(nlohmann::json::parse("2000.5"), "simulation.max_steps", out));
  EXPECT_FALSE(fields.integer(nlohmann::json::parse("1e30"), "simulation.max_steps", out));
  EXPECT_FALSE(fields.integer(nlohmann::json::parse("\"7\""), "simulation.window", out));
  std::ostringstream printed;
  diagnostics.print(printed);
  EXPECT_NE(printed.str().find("simulation.max_steps: expected an integer, got 2000.5"),
            std::string::npos)
      << printed.str();
  EXPECT_NE(printed.str().find("simulation.max_steps: integer out of range"), std::string::npos)
      << printed.str();
  EXPECT_NE(printed.str().find("simulation.window: expected an integer, got string"),
            std::string::npos)
      << printed.str();
}

TEST(ParseJson, ReportsMalformedJsonWithItsPosition) {
  Diagnostics diagnostics;
  EXPECT_FALSE(parseJson("{\n  \"a\": [1, 2,\n}", "tracings.json", diagnostics));
  std::ostringstream printed;
  diagnostics.print(printed);
  EXPECT_NE(printed.str().find("tracings.json: line 3"), std::string::npos) << printed.str();
}

// nlohmann keeps the last of a key given twice without a word: a case.json with two "mesh"
// keys read the second mesh.
TEST(ParseJson, RefusesADuplicateKeyNamingItsPath) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"mesh": "a.ply", "version": 1, "mesh": "b.ply"})", "mesh"},
      {R"({"tips": [], "cords": [{"tip": 0}, {"tip": 0, "rest_length_mm": 20,
          "point": {"weights": [1, 0, 0]}, "rest_length_mm": 1e-300}]})",
       "cords[1].rest_length_mm"},
      {R"({"tracings": [[1, {"a": 1}], [[2], {"plane": {"normal": [0, 1, 0], "origin": [],
          "normal": [1, 0, 0]}}]]})",
       "tracings[1][1].plane.normal"},
      {R"([{"x": 1}, {"y": {"z": 1, "z": 2, "z": 3}}])", "[1].y.z"}};
  for (const auto& [text, where] : cases) {
    Diagnostics diagnostics;
    EXPECT_FALSE(parseJson(text, "case.json", diagnostics)) << text;
    ASSERT_EQ(diagnostics.problems().size(), 1u) << text;
    const Problem& p = diagnostics.problems().front();
    EXPECT_EQ(p.file, "case.json");
    EXPECT_EQ(p.where, where);
    EXPECT_EQ(p.what,
              "duplicate key: given more than once in this object, and only one of its values "
              "would be read: keep one");
  }
}

TEST(ParseJson, AcceptsTheSameKeyInDifferentObjects) {
  Diagnostics diagnostics;
  const auto document = parseJson(
      R"({"a": {"x": 1}, "b": {"x": 2, "a": {"x": 3}}, "c": [{"x": 4}, {"x": 5}], "x": 6})",
      "case.json", diagnostics);
  ASSERT_TRUE(document);
  EXPECT_TRUE(diagnostics.ok());
  EXPECT_EQ((*document)["c"][1]["x"], 5);
}

TEST(ParseJson, CapsTheDuplicateKeysItNames) {
  std::string text = "{";
  for (int k = 0; k < 25; ++k)
    text += "\"k" + std::to_string(k) + "\": 1, \"k" + std::to_string(k) + "\": 2, ";
  text += "\"end\": 0}";
  Diagnostics diagnostics;
  EXPECT_FALSE(parseJson(text, "cords.json", diagnostics));
  ASSERT_EQ(diagnostics.problems().size(), 11u);
  EXPECT_EQ(diagnostics.problems().front().where, "k0");
  EXPECT_EQ(diagnostics.problems().back().what, "15 more duplicate keys");
}

// A directory used to be opened and "parsed" (line 1, column 1: malformed JSON) and a device
// such as /dev/zero read until the machine ran out of memory.
TEST(LoadJsonFile, RefusesAnEmptyPathADirectoryADeviceAndAHugeFileNamingTheFile) {
  testing::TempDir dir;
  std::filesystem::create_directory(dir / "cords.json");
  { std::ofstream(dir / "huge.json").put('['); }
  std::filesystem::resize_file(dir / "huge.json", kMaxInputFileBytes + 1);  // sparse
  const std::pair<std::filesystem::path, std::string> cases[] = {
      {"", "given.json: no file given"},
      {dir / "cords.json", "given.json: is a directory, not a JSON file"},
      {"/dev/null", "given.json: is not a regular file"},
      {dir / "huge.json", "given.json: is larger than 512 MiB, the most an input file may have"}};
  for (const auto& [path, message] : cases) {
    Diagnostics diagnostics;
    EXPECT_FALSE(loadJsonFile(path, "given.json", diagnostics)) << path;
    std::ostringstream printed;
    diagnostics.print(printed);
    EXPECT_NE(printed.str().find("error: " + message), std::string::npos) << printed.str();
    EXPECT_EQ(printed.str().find("malformed JSON"), std::string::npos) << printed.str();
  }
}

}  // namespace
}  // namespace chordfit
