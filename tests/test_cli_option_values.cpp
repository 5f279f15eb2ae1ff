// Every numeric option of the commands that take one, read from the command's own --help, given
// values a typo or a script can produce: not a number, infinities, negative, zero, huge, tiny,
// past 2^64 and a word. Each run must be accepted, or refused with exit 2 naming the option,
// and never crash, exit 1 or print an infinite, NaN or 300-digit quantity. Written after such a
// sweep by hand found a fit that returned its seed with exit 0 (--section-weight 1e308), a
// make-valve that wrote a case validate refused (--anterior-height 1e-300) and a seed that
// saturated silently (--seed 99999999999999999999).
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "tests/test_support.h"

namespace chordfit {
namespace {

using testing::quoted;
using testing::runChordfit;
using testing::TempDir;

const char* const kValues[] = {
    "nan", "inf", "-inf", "-1", "0", "1e308", "1e-300", "99999999999999999999", "x"};

// The options of `command --help` whose value is a number (CLI11 types them FLOAT, INT or UINT).
std::vector<std::string> numericOptions(const std::string& command) {
  const auto help = runChordfit(command + " --help");
  EXPECT_EQ(help.exit_code, 0) << help.err;
  std::vector<std::string> options;
  std::istringstream lines(help.out);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string option, type;
    words >> option >> type;
    if (option.rfind("--", 0) == 0 &&
        (type.rfind("FLOAT", 0) == 0 || type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0))
      options.push_back(option);
  }
  return options;
}

// The longest run of digits in `text` (a 1e308 printed with %f has 309).
std::size_t longestDigitRun(const std::string& text) {
  std::size_t longest = 0, run = 0;
  for (char c : text) {
    run = std::isdigit(static_cast<unsigned char>(c)) ? run + 1 : 0;
    longest = std::max(longest, run);
  }
  return longest;
}

struct CommandUnderTest {
  std::string name;
  // Before the option: the case, a cheap workload (accepted values do the work) and --out.
  std::string arguments;
};

class NumericOptionValues : public ::testing::TestWithParam<CommandUnderTest> {};

TEST_P(NumericOptionValues, AreAcceptedOrRefusedNamingTheOptionNeverACrash) {
  const CommandUnderTest& command = GetParam();
  TempDir dir;
  const std::filesystem::path valve = dir / "valve";
  ASSERT_EQ(runChordfit("make-valve --edge 3 --out " + quoted(valve)).exit_code, 0);
  const std::filesystem::path small = std::filesystem::path(CHORDFIT_CASES_DIR) / "small-normal";
  std::string arguments = command.arguments;
  for (const auto& [name, path] : {std::pair{"VALVE", valve}, std::pair{"SMALL", small}})
    if (const auto at = arguments.find(name); at != std::string::npos)
      arguments.replace(at, std::string(name).size(), quoted(path));
  const std::vector<std::string> options = numericOptions(command.name);
  ASSERT_GE(options.size(), 1u) << command.name;
  int runs = 0;
  for (const std::string& option : options) {
    // The workload's own value of the option (--max-sims 2) gives way to the one under test.
    std::string workload = " " + arguments + " ";
    if (const auto at = workload.find(" " + option + " "); at != std::string::npos)
      workload.erase(at, workload.find(' ', at + option.size() + 2) - at);
    for (const char* value : kValues) {
      const std::filesystem::path out = dir / ("out" + std::to_string(runs++));
      const std::string line =
          command.name + workload + "--out " + quoted(out) + " " + option + "=" + value;
      const auto r = runChordfit(line);
      SCOPED_TRACE(line + "\nstdout:\n" + r.out + "stderr:\n" + r.err);
      EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 2 || r.exit_code == 3);
      if (r.exit_code == 2) {
        EXPECT_NE(r.err.find("error: "), std::string::npos);
        EXPECT_NE(r.err.find(option), std::string::npos) << "the refusal names " << option;
        EXPECT_FALSE(std::filesystem::exists(out) && !std::filesystem::is_empty(out))
            << "refused, yet wrote into --out";
      }
      const std::string text = r.out + r.err;
      for (const char* bad : {"inf mm", "nan mm", "terminate called", "what():"})
        EXPECT_EQ(text.find(bad), std::string::npos) << bad;
      EXPECT_LT(longestDigitRun(text), 40u) << "a number printed with hundreds of digits";
    }
  }
}

// The workloads keep an accepted value cheap: a 3 mm valve, two forward runs, a two-step sweep.
INSTANTIATE_TEST_SUITE_P(
    Commands, NumericOptionValues,
    ::testing::Values(
        CommandUnderTest{"make-valve", ""}, CommandUnderTest{"heuristic", "VALVE"},
        CommandUnderTest{"simulate", "VALVE --quiet"},
        CommandUnderTest{"sweep-cord", "SMALL --range 0.002 --step 0.001 --window 2"},
        CommandUnderTest{"make-case", "--preset normal-1 --edge 3 --planes 2 --quiet"},
        CommandUnderTest{"fit", "SMALL --max-sims 2 --no-prefit --no-uncertainty --quiet"}),
    [](const ::testing::TestParamInfo<CommandUnderTest>& info) {
      std::string name = info.param.name;
      name.erase(std::remove(name.begin(), name.end(), '-'), name.end());
      return name;
    });

}  // namespace
}  // namespace chordfit
