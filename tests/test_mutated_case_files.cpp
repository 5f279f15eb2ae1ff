// A case's JSON files with one value spoilt, as a hand edit or a script gone wrong spoils them:
// a number made huge, tiny, negative or zero, a value made a string, null, a boolean, an array
// or an object, or a key or list entry removed. `chordfit validate` accepts the case or refuses
// it with an error naming the spoilt file (exit 2), never crashes. The same mutations run by
// hand over the bundled cases (1,300 validate runs) found a coordinate near 1e308 reported as
// "inf mm" away; this keeps the whole family from coming back.
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::quoted;
using testing::readText;
using testing::runChordfit;
using testing::TempDir;
using testing::writeText;

// The JSON pointers of every leaf (number, string, boolean, null, empty array or object).
void collectLeaves(const json& value, const json::json_pointer& at,
                   std::vector<json::json_pointer>& leaves) {
  if (value.is_object() && !value.empty()) {
    for (const auto& [key, child] : value.items()) collectLeaves(child, at / key, leaves);
  } else if (value.is_array() && !value.empty()) {
    for (std::size_t k = 0; k < value.size(); ++k) collectLeaves(value[k], at / k, leaves);
  } else {
    leaves.push_back(at);
  }
}

// True when a line of `err` starting "error: " mentions `file`.
bool anErrorMentions(const std::string& err, const std::string& file) {
  std::istringstream lines(err);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("error: ", 0) == 0 && line.find(file) != std::string::npos) return true;
  return false;
}

// Removes the value at `at` from its object or array.
void eraseAt(json& document, const json::json_pointer& at) {
  json& parent = document[at.parent_pointer()];
  if (parent.is_object())
    parent.erase(at.back());
  else
    parent.erase(std::stoul(at.back()));
}

TEST(MutatedCaseFiles, AreAcceptedOrRefusedNamingTheSpoiltFileNeverACrash) {
  const fs::path bundled = fs::path(CHORDFIT_CASES_DIR) / "small-normal";
  ASSERT_TRUE(fs::exists(bundled / "case.json"))
      << bundled << ": bundled case missing (cmake --build BUILD --target cohort_cases)";
  TempDir dir;
  const fs::path case_dir = dir / "case";
  fs::copy(bundled, case_dir, fs::copy_options::recursive);

  const std::vector<std::string> files = {"case.json",           "annulus_ring.json",
                                          "annulus_closed.json", "leaflets.json",
                                          "cords.json",          "tracings.json"};
  const std::vector<json> spoilers = {1e308, -1e308,        1e-300,        -1.0,
                                      0,     4294967296LL,  "x",           nullptr,
                                      true,  json::array(), json::object()};
  std::mt19937 rng(20261129);
  int refused = 0, accepted = 0;
  constexpr int kTrials = 160;
  for (int trial = 0; trial < kTrials; ++trial) {
    const std::string& file = files[rng() % files.size()];
    const std::string original = readText(case_dir / file);
    json document = json::parse(original);
    std::vector<json::json_pointer> leaves;
    collectLeaves(document, json::json_pointer(), leaves);
    const json::json_pointer at = leaves[rng() % leaves.size()];
    const std::size_t how = rng() % (spoilers.size() + 1);  // the last: remove it
    std::string change;
    if (how == spoilers.size()) {
      eraseAt(document, at);
      change = at.to_string() + " removed";
    } else {
      document[at] = spoilers[how];
      change = at.to_string() + " = " + spoilers[how].dump();
    }
    writeText(case_dir / file, document.dump(1));

    const auto r = runChordfit("validate " + quoted(case_dir));
    const std::string what = "trial " + std::to_string(trial) + ": " + file + " " + change;
    ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 2) << what << ": exit " << r.exit_code << "\n"
                                                      << r.err;
    if (r.exit_code == 2) {
      ++refused;
      // "error: <file>: <where>: <problem>" (under "case <dir>: N problem(s)"): an error names
      // the spoilt file, as its own or, for a change that makes another file wrong (a leaflet
      // renamed in case.json, which tracings.json names), in its text.
      EXPECT_TRUE(anErrorMentions(r.err, file)) << what << "\n" << r.err;
      // A distance or length that overflowed reads as "inf mm", one of NaN as "nan mm".
      EXPECT_EQ(r.err.find("inf mm"), std::string::npos) << what << "\n" << r.err;
      EXPECT_EQ(r.err.find("nan mm"), std::string::npos) << what << "\n" << r.err;
    } else {
      ++accepted;
    }
    writeText(case_dir / file, original);
  }
  // The spoilt values reach the checks (and not every change is fatal: a tracing point moved
  // to 0 may still lie on its plane near the valve).
  EXPECT_GT(refused, kTrials / 2);
  EXPECT_GT(accepted, 0);
}

}  // namespace
}  // namespace chordfit
