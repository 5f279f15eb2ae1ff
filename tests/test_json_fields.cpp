#include <sstream>

#include <gtest/gtest.h>

#include "core/json_fields.h"

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

}  // namespace
}  // namespace chordfit
