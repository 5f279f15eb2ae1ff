// The command line's own messages and the options added for them: what a refused value says
// (the option, what it must be, the value given), notes on options that do not act, metrics
// --set, compare --threads. Every run here is a parse error, a refusal before any closure, or
// a closure of the bundled small case (about a second).
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;
using testing::quoted;
using testing::readText;
using testing::runChordfit;
using testing::TempDir;

// The bundled small test case (cases/CMakeLists.txt: normal-1 seed 2, edge 3 mm, 3 planes).
fs::path smallCase() { return fs::path(CHORDFIT_CASES_DIR) / "small-normal"; }

// Where the line starting with `prefix` that reports a finished closure (" after N steps")
// begins in `text`; npos when there is none.
std::size_t finishedLine(const std::string& text, const std::string& prefix) {
  for (std::size_t at = text.find(prefix); at != std::string::npos; at = text.find(prefix, at + 1))
    if (text.substr(at, text.find('\n', at) - at).find(" after ") != std::string::npos) return at;
  return std::string::npos;
}

// A refusal: exit 2 and `message` on stderr.
void expectRefused(const std::string& arguments, const std::string& message) {
  const auto r = runChordfit(arguments);
  EXPECT_EQ(r.exit_code, 2) << arguments << "\n" << r.out << r.err;
  EXPECT_NE(r.err.find(message), std::string::npos) << arguments << "\nstderr:\n" << r.err;
}

// simulate --set thickness_mm=2 closes the valve with thicker leaflets, which the orifice
// coverage grows the mid-surface by; metrics of that closed mesh measured the default
// thickness and reported another coverage than simulate did.
TEST(MetricsCommand, TakesTheSimulatorOverridesSimulateClosedTheMeshWith) {
  TempDir dir;
  const std::string set = " --set thickness_mm=2";
  auto r = runChordfit("simulate " + quoted(smallCase()) + set + " --quiet --out " +
                       quoted(dir / "sim"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto simulated = nlohmann::json::parse(readText(dir / "sim" / "metrics.json"));
  const std::string measure =
      "metrics " + quoted(smallCase()) + " --mesh " + quoted(dir / "sim" / "closed.ply");
  r = runChordfit(measure + set + " --out " + quoted(dir / "with_set.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto measured = nlohmann::json::parse(readText(dir / "with_set.json"));
  EXPECT_EQ(measured["orifice_tissue_radius_mm"], simulated["orifice_tissue_radius_mm"]);
  EXPECT_EQ(measured["orifice_coverage"], simulated["orifice_coverage"]);
  // Without it, the default thickness: the check above is not vacuous.
  r = runChordfit(measure + " --out " + quoted(dir / "without.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto by_default = nlohmann::json::parse(readText(dir / "without.json"));
  EXPECT_NE(by_default["orifice_tissue_radius_mm"], simulated["orifice_tissue_radius_mm"]);
  // And a bad override is refused as simulate refuses it.
  expectRefused(measure + " --set thickness_mm=0", "metrics: --set");
}

// "Value 2.5 not in range 1 to 64" named neither the option's kind nor its place; fit had
// messages of its own.
TEST(ThreadsOption, IsAnIntegerFrom1To64InEveryCommandNamingTheValue) {
  TempDir dir;
  const std::string out = " --out " + quoted(dir / "out");
  const std::string case_dir = " " + quoted(smallCase());
  const std::vector<std::string> commands = {
      "simulate" + case_dir, "sweep-cord" + case_dir, "make-case --preset normal-1",
      "fit" + case_dir, "compare" + case_dir + " " + quoted(smallCase() / "cords.json")};
  for (const std::string& command : commands)
    for (const std::string value : {"2.5", "abc", "0", "65", "-1"}) {
      const std::string name = command.substr(0, command.find(' '));
      expectRefused(command + " --threads " + value + out,
                    "error: " + name + ": --threads: must be an integer in [1, 64], got " + value);
    }
  EXPECT_FALSE(fs::exists(dir / "out"));
  // One help line pattern for all.
  for (const std::string command : {"simulate", "sweep-cord", "make-case", "fit", "compare"}) {
    const auto help = runChordfit(command + " --help");
    EXPECT_NE(help.out.find("1-64; the same result for any count"), std::string::npos)
        << command << ":\n"
        << help.out;
  }
}

// The cord sets' closures run in parallel; the results go to their own slots, so the output is
// the same, byte for byte, for any thread count.
TEST(CompareThreads, WritesTheSameBytesForOneAndTwoThreads) {
  TempDir dir;
  nlohmann::json cords = nlohmann::json::parse(readText(smallCase() / "cords.json"));
  for (auto& cord : cords["cords"]) {
    cord["rest_length_mm"] = 1.2 * cord["rest_length_mm"].get<double>();
    cord["scale"] = 1.2;
    cord["provenance"] = "manual";
  }
  testing::writeText(dir / "longer.json", cords.dump(1));
  const std::string compare = "compare " + quoted(smallCase()) + " " +
                              quoted(smallCase() / "cords.json") + " " +
                              quoted(dir / "longer.json") + " --labels seed,longer";
  const auto one = runChordfit(compare + " --threads 1 --out " + quoted(dir / "one"));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const auto two = runChordfit(compare + " --threads 2 --out " + quoted(dir / "two"));
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_EQ(one.out.substr(0, one.out.find("wrote ")), two.out.substr(0, two.out.find("wrote ")));
  for (const std::string file :
       {"compare.md", "compare.csv", "cords.csv", "sections.svg", "enface_1.svg", "enface_2.svg"})
    EXPECT_EQ(readText(dir / "one" / file), readText(dir / "two" / file)) << file;
  // Progress in the order given, whichever closure ends first.
  EXPECT_NE(finishedLine(two.err, "compare: [2/2] longer: "), std::string::npos) << two.err;
  EXPECT_LT(finishedLine(two.err, "compare: [1/2] seed: "),
            finishedLine(two.err, "compare: [2/2] longer: "))
      << two.err;
}

// --ap and --cc shape the parametric annulus only; with --annulus they were dropped silently.
TEST(MakeValveCommand, NotesDiametersTheAnnulusFileOverridesAndListsItsFormats) {
  TempDir dir;
  const std::string annulus = " --annulus " + quoted(smallCase() / "annulus_closed.json");
  auto r = runChordfit("make-valve --edge 3" + annulus + " --ap 30 --out " + quoted(dir / "a"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: make-valve: --ap does not act with --annulus"), std::string::npos)
      << r.err;
  r = runChordfit("make-valve --edge 3" + annulus + " --ap 30 --cc 36 --out " + quoted(dir / "b"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: make-valve: --ap and --cc do not act with --annulus"),
            std::string::npos)
      << r.err;
  // Nor do they bound the saddle heights then (--ap 10 refused the default closed saddle).
  r = runChordfit("make-valve --edge 3" + annulus + " --ap 10 --out " + quoted(dir / "d"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = runChordfit("make-valve --edge 3" + annulus + " --out " + quoted(dir / "c"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("note:"), std::string::npos) << r.err;
  const auto help = runChordfit("make-valve --help");
  for (const char* format : {"JSON", ".mrk.json", ".csv", ".fcsv", ".txt"})
    EXPECT_NE(help.out.find(format), std::string::npos) << format << "\n" << help.out;
}

// An --out within the system's path limit but not within it once the staging directory, the
// file names and temporary suffixes are added is refused before the work, and nothing is made
// (simulate failed after its closure, exit 1, and left the directories it had created).
TEST(Cli, RefusesAnOutputPathTooLongForWhatIsWrittenUnderItBeforeTheWork) {
  TempDir dir;
  fs::path out = dir.path();
  while (out.string().size() < 3800) out /= std::string(199, 'd');
  out /= std::string(4068 - out.string().size() - 1, 'e');
  ASSERT_EQ(out.string().size(), 4068u);
  const std::string message =
      ": a path of 4068 bytes: the paths written under it (a staging "
      "directory and temporary names included) would pass the system's "
      "limit of 4095 bytes; give a shorter path";
  expectRefused("simulate " + quoted(smallCase()) + " --out " + quoted(out),
                "error: simulate: --out: " + out.string() + message);
  // A single file has no staging directory: refused nearer the limit.
  fs::path file = dir.path();
  while (file.string().size() < 3880) file /= std::string(199, 'd');
  file /= std::string(4085 - file.string().size() - 1, 'f');
  ASSERT_EQ(file.string().size(), 4085u);
  expectRefused("heuristic " + quoted(smallCase()) + " --out " + quoted(file),
                "error: heuristic: --out: " + file.string() +
                    ": a path of 4085 bytes: its temporary name while it is written would pass "
                    "the system's limit of 4095 bytes; give a shorter path");
  // A file name legal on its own that its temporary name takes past NAME_MAX.
  const fs::path long_name = dir.path() / (std::string(245, 'c') + ".json");
  expectRefused("heuristic " + quoted(smallCase()) + " --out " + quoted(long_name),
                "error: heuristic: --out: " + long_name.string() +
                    ": a file name of 250 bytes: its temporary name while it is written would "
                    "pass the system's limit of 255 bytes for a name; give a name of at most 230 "
                    "bytes");
  EXPECT_TRUE(fs::is_empty(dir.path())) << "nothing made";
}

// `chordfit --bogus` said only "A subcommand is required".
// A missing cord or tissue file is named with the command and option that gave it: the bare
// "error: nope.json: file not found" did not say which of two JSON files was meant.
TEST(Cli, NamesTheOptionOfAMissingCordOrTissueFile) {
  TempDir dir;
  const std::string missing = quoted(dir / "nope.json");
  const std::string case_dir = quoted(smallCase());
  const std::string out = " --out " + quoted(dir / "out");
  const std::string named = ": " + (dir / "nope.json").string() + ": file not found";
  expectRefused("simulate " + case_dir + " --cords " + missing + out,
                "error: simulate: --cords" + named);
  expectRefused("simulate " + case_dir + " --tissue " + missing + out,
                "error: simulate: --tissue" + named);
  expectRefused("sweep-cord " + case_dir + " --cords " + missing + out,
                "error: sweep-cord: --cords" + named);
  expectRefused("fit " + case_dir + " --seed-cords " + missing + out,
                "error: fit: --seed-cords" + named);
  expectRefused("edit-cords " + case_dir + " --cords " + missing + " --all 1.1 --out " +
                    quoted(dir / "e.json"),
                "error: edit-cords: --cords" + named);
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(Cli, NamesAnUnknownOptionBeforeTheCommand) {
  expectRefused("--bogus", "error: unknown option --bogus");
  expectRefused("--verison", "--verison: did you mean \"--version\"?");
  expectRefused("--bogus=1 simulate x --out y", "error: unknown option --bogus");
  expectRefused("", "error: a command is required");
}

// "make-case prolapse-P2 --out D": the preset without its option.
TEST(MakeCaseCommand, HintsThePresetOptionForABarePresetName) {
  TempDir dir;
  expectRefused("make-case prolapse-P2 --out " + quoted(dir / "case"),
                "did you mean \"--preset prolapse-P2\"?");
  EXPECT_FALSE(fs::exists(dir / "case"));
}

TEST(MakeCaseCommand, NamesTheValueOfARefusedTracingOption) {
  TempDir dir;
  const std::string make = "make-case --preset normal-1 --quiet --out " + quoted(dir / "c");
  expectRefused(make + " --planes 40", "error: make-case: --planes: must be in [1, 36], got 40");
  expectRefused(make + " --noise 6", "error: make-case: --noise: must be in [0, 5] mm, got 6");
  expectRefused(make + " --dropout 0.95",
                "error: make-case: --dropout: must be in [0, 0.9], got 0.95");
}

TEST(SweepCordCommand, NamesTheOptionAndValueOfARefusedRangeStepOrCord) {
  TempDir dir;
  const std::string sweep = "sweep-cord " + quoted(smallCase()) + " --out " + quoted(dir / "s");
  expectRefused(sweep + " --range 0.6", "error: sweep-cord: --range: must be in (0, 0.5), got 0.6");
  expectRefused(sweep + " --range 0.05 --step 0.1",
                "error: sweep-cord: --range/--step: --step must be in (0, --range 0.05], got 0.1");
  const auto cords = nlohmann::json::parse(readText(smallCase() / "cords.json"))["cords"].size();
  expectRefused(sweep + " --cord 999", "error: sweep-cord: --cord: no such cord 999 (the set has " +
                                           std::to_string(cords) + " cords: 0.." +
                                           std::to_string(cords - 1) + ")");
  const auto help = runChordfit("sweep-cord --help");
  EXPECT_NE(help.out.find("--cord INT "), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--quiet"), std::string::npos) << help.out;
}

// CLI11's own words ("Could not convert: --edge = abc", "At Most 1 required but received 2",
// "The following argument was not expected") in the form of the commands' checks.
TEST(Cli, RewordsTheCommonParseErrors) {
  TempDir dir;
  const std::string valve = "make-valve --out " + quoted(dir / "v");
  expectRefused(valve + " --edge abc",
                "error: make-valve: --edge: expected a number, got 'abc' (chordfit make-valve "
                "--help)");
  expectRefused(valve + " --edge 2 --edge 3",
                "error: make-valve: --edge: given 2 times; give it once");
  expectRefused(valve + " stray", "error: make-valve: unexpected argument \"stray\"");
  const std::string fit = "fit " + quoted(smallCase()) + " --out " + quoted(dir / "f");
  expectRefused(fit + " --max-sims 2.5", "error: fit: --max-sims: expected an integer, got '2.5'");
  expectRefused(fit + " --scale-bounds x,1",
                "error: fit: --scale-bounds: expected two numbers LO,HI, got 'x,1'");
  expectRefused(fit + " --scale-bounds 0.5,1.5 --scale-bounds 0.6,1.4",
                "error: fit: --scale-bounds: given 2 times; give it once");
  expectRefused(fit + " --scale-bounds 1.5,0.7",
                "error: fit: --scale-bounds: need two numbers 0 < LO < HI, got 1.5,0.7");
  // Given once, with four values: not "given 2 times".
  expectRefused(fit + " --scale-bounds 0.5,1.2,0.6,1.3",
                "error: fit: --scale-bounds: expected two numbers LO,HI, got 4 values");
  EXPECT_FALSE(fs::exists(dir / "v"));
  EXPECT_FALSE(fs::exists(dir / "f"));
}

// An integer option takes an integral value in exponent form, as a case's integer settings do
// (docs/case-format.md): --max-sims 1e3 reaches the fit's own checks (here: --params).
TEST(Cli, IntegerOptionsTakeIntegralValuesInExponentForm) {
  TempDir dir;
  const std::string fit =
      "fit " + quoted(smallCase()) + " --params bogus --out " + quoted(dir / "f");
  expectRefused(fit + " --max-sims 1e3 --threads 2e0", "error: fit: --params: expected scales");
  expectRefused(fit + " --max-sims 1.5e0",
                "error: fit: --max-sims: expected an integer, got '1.5e0'");
  // Base 10 always: "+2" and "02" are 2, a hexadecimal value is no integer of this CLI (CLI11
  // alone read "077" as octal 63 and took "0x2").
  expectRefused(fit + " --max-sims +1000 --threads 02", "error: fit: --params: expected scales");
  expectRefused(fit + " --threads 0x2",
                "error: fit: --threads: must be an integer in [1, 64], got 0x2");
  expectRefused(fit + " --max-sims 0x2", "error: fit: --max-sims: expected an integer, got '0x2'");
  expectRefused("make-case --preset normal-1 --planes 077 --out " + quoted(dir / "c"), "got 77");
  // Beyond the option's type: the value as given, not as rewritten.
  expectRefused(fit + " --max-sims 1e10",
                "error: fit: --max-sims: must be at most 2147483647, got 1e10");
  expectRefused(fit + " --max-sims -99999999999",
                "error: fit: --max-sims: must be at least -2147483648, got -99999999999");
  expectRefused(fit + " --threads 1e308",
                "error: fit: --threads: must be an integer in [1, 64], got 1e308");
}

// A case without tracings names its case.json as every case problem does ("DIR/case.json:
// tracings: ..."; it read "DIR: case.json: tracings"), and nothing is written.
TEST(FitCommand, NamesTheCaseFileOfACaseWithoutTracings) {
  TempDir dir;
  ASSERT_EQ(runChordfit("make-valve --edge 3 --out " + quoted(dir / "valve")).exit_code, 0);
  expectRefused(
      "fit " + quoted(dir / "valve") + " --out " + quoted(dir / "fit"),
      "error: " + (dir / "valve" / "case.json").string() + ": tracings: the fit needs tracings");
  EXPECT_FALSE(fs::exists(dir / "fit"));
}

// A refused value is refused first; the note that the option does not act in this fit came
// before the error.
TEST(FitCommand, ChecksValuesBeforeNotingOptionsThatDoNotAct) {
  TempDir dir;
  const auto r =
      runChordfit("fit " + quoted(smallCase()) + " --tip-weight -1 --out " + quoted(dir / "f"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: fit: --tip-weight: must be in [0, 1000], got -1"), std::string::npos)
      << r.err;
  EXPECT_EQ((r.out + r.err).find("note: fit: --tip-weight"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace chordfit
