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

TEST(ParseJson, ReportsMalformedJsonWithItsPosition) {
  Diagnostics diagnostics;
  EXPECT_FALSE(parseJson("{\n  \"a\": [1, 2,\n}", "tracings.json", diagnostics));
  std::ostringstream printed;
  diagnostics.print(printed);
  EXPECT_NE(printed.str().find("tracings.json: line 3"), std::string::npos) << printed.str();
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
