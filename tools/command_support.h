// Small pieces every command shares: loading a case with errors printed, summaries.
#pragma once

#include <initializer_list>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/case_data.h"
#include "core/diagnostics.h"
#include "core/metrics.h"
#include "core/simulator.h"

namespace chordfit::cli {

// Loads and validates a case; on problems prints them ("error: file: where: what") to stderr
// and returns nullopt.
std::optional<ValveCase> loadCaseOrReport(const std::string& case_dir);

// Prints the diagnostics to stderr and returns kExitBadInput.
int reportProblems(const Diagnostics& diagnostics);

// The cord set a command works with: `cords_file` when given (checked against the case
// mesh), else the case's own cords, else the paper's heuristic. Prints problems and returns
// nullopt on bad input. `given_as` ("simulate: --cords"), when given, names a missing file's
// option: a command may read two files of the same kind of name (cords.json, tissue.json).
std::optional<CordSet> resolveCords(const ValveCase& valve_case, const std::string& cords_file,
                                    const std::string& given_as = "");

// False, with "error: GIVEN_AS: FILE: file not found" printed, when `file` does not exist;
// true otherwise (any other problem is its reader's to report).
bool optionFileFoundOrReport(const std::string& given_as, const std::string& file);

// Why resolveCords' set cannot be worked on when it has no cords, naming where it came from:
// "E.json has no cords", "CASE: the case's cord set has no cords (give OPTION)" or "CASE: the
// heuristic placed no cords on this mesh". `option`: how the command takes a cord file.
std::string noCordsProblem(const ValveCase& valve_case, const std::string& case_dir,
                           const std::string& cords_file, const char* option);

// Notes go to stderr, in every command: stdout carries what the command makes (progress,
// tables, summaries), stderr what the user may want to know about it (errors, warnings,
// notes). stdout is flushed first, so that a log of both streams (2>&1) keeps each note
// after the lines printed before it. printNote and printWarning print "note: " or "warning: "
// and the formatted text (give it its newline); printLinesToStderr prints lines that already
// start with "note: " or "warning: " as they are.
void printNote(const char* format, ...) __attribute__((format(printf, 1, 2)));
void printWarning(const char* format, ...) __attribute__((format(printf, 1, 2)));
void printLinesToStderr(const std::string& lines);

// A note when a fit's tissue.json lies beside `cords_file` (a fit's output directory) and the
// command closes those cords on the case's own tissue instead: the fit closed them on that
// tissue (its tissue pre-fit or tissue retry softened a segment), so this closure is not the
// fit's. `option` is how the command takes a tissue file ("--tissue FILE", "--tissues …").
// "" when there is no such file or no cords file.
std::string tissueBesideCordsNote(const char* command, const std::string& cords_file,
                                  const std::string& option);

// What simulate and sweep-cord close: the case (loadCaseOrReport) with `tissue_file` over its
// own tissue when given, and the cords (resolveCords). Without a tissue file it prints
// tissueBesideCordsNote, so that cords a fit closed on its own tissue are not taken for its
// closure silently. Prints problems and returns nullopt on bad input.
struct CaseWithCords {
  ValveCase valve_case;
  CordSet cords;
};
std::optional<CaseWithCords> loadCaseWithCords(const char* command, const std::string& case_dir,
                                               const std::string& tissue_file,
                                               const std::string& cords_file);

// The case's simulator settings (its "simulation" block over the defaults), then the
// command line's `overrides` ("KEY=VALUE": a key of that block and a number, true or false;
// `--set`), which are also written into valve_case.simulation_json so that everything reading
// the case's settings later sees them; phase kClose. On unknown keys, wrong types,
// out-of-range values or a pressure ramp longer than the step cap (not checked when `use` is
// kMeasure) prints the problems under "case CASE_DIR: N problem(s)", naming case.json,
// "<command>: --set" or, when its stiffness factors shorten the automatic time step, the tissue
// (`tissue_file`, the --tissue file over the case's own tissue, or case.json's
// tissue_stiffness), and returns nullopt. With kClose it also notes a pressure loaded faster
// than the ramp was calibrated for.
enum class SettingsUse {
  kCheck,    // validate: every check, no closure run now
  kMeasure,  // metrics: reads the settings (the leaflets' thickness), runs no closure
  kClose,    // simulate, sweep-cord, fit, compare: closures run now
};
std::optional<SimulationSettings> caseSettingsOrReport(
    ValveCase& valve_case, const std::string& case_dir, SettingsUse use, const char* command = "",
    const std::vector<std::string>& overrides = {}, const std::string& tissue_file = "");

// After a tissue file has replaced `valve_case`'s tissue (compare --tissues, one per cord set,
// read after caseSettingsOrReport): whether the pressure ramp still fits under the step cap of
// `settings`; otherwise reports it at `tissue_file` as caseSettingsOrReport does and returns
// false (a stiff file was blamed on the cord file, once its closure ran).
bool tissueStepCapOrReport(const ValveCase& valve_case, const SimulationSettings& settings,
                           const std::string& tissue_file);

// Whether `option` ("--ap") is among the options given on the command line (the options
// structs' given_options), for a command's notes on options that do not act.
inline bool optionGiven(const std::vector<std::string>& given_options, const char* option) {
  for (const std::string& given : given_options)
    if (given == option) return true;
  return false;
}

// Each (option, value) must be a finite number > 0; the first that is not gets
// "error: <command>: <option>: must be <what>, got <value>" on stderr. Returns whether all are.
bool optionsArePositive(const char* command,
                        std::initializer_list<std::pair<const char*, double>> options,
                        const char* what);

// Whether the outputs can go to `directory` (created later if missing): its nearest existing
// ancestor must be a writable directory, and none of the `files` the command writes there may
// be an existing directory (the final rename onto it would fail after the work) nor go into a
// subdirectory where a file stands, and no missing part of it may be a symbolic link to
// nowhere. On a problem prints
// "error: <command>: --out: <path>: <reason>" ("--out: must not be empty" for "") and
// returns false. Checked before the work starts, so that a fit does not run for minutes and
// then fail to write.
// `inputs`: the files the run reads (caseInputFiles, --cords, ...); an output that would
// replace one of them is refused too ("is an input of this run"): `fit CASE --out CASE` would
// replace the case's own cords.json, a seed put in --out would be lost to the fitted cords.
bool outputDirectoryUsable(const char* command, const std::string& directory,
                           const std::vector<std::string>& files = {},
                           const std::vector<std::string>& inputs = {});

// A case's own files: case.json and every file it names that exists in the case directory;
// without its cords file (the "cords" entry) when `with_cords` is false.
std::vector<std::string> caseInputFiles(const std::string& case_dir, bool with_cords = true);

// Whether `output` is one of `inputs` (the same file, through any path or link); on a problem
// prints "error: <command>: --out: <output>: is an input of this run; ..." and returns false.
bool outputSparesInputs(const char* command, const std::string& output,
                        const std::vector<std::string>& inputs);

// The same for an output file: its directory must be usable as above and the file itself must
// not be an existing directory (the final rename would fail after the work) nor a symbolic
// link to nowhere (the rename would replace the link, not write its target).
bool outputFileUsable(const char* command, const std::string& file);

// The files of a case directory (make-valve, import-mesh, make-case) besides `declared`, the
// ones a command writing it declares: an earlier case's there, e.g. make-case's truth/ under a
// new make-valve case, would describe another valve, so they go with it (StagedOutput's
// `superseded`; only files a chordfit run published).
std::vector<std::string> caseDirectoryFilesBesides(const std::vector<std::string>& declared);

// For a case a command writes (make-valve, import-mesh): a fine mesh's automatic time step
// can make the default step cap end before, or soon after, the pressure ramp. Then the case
// gets simulation.max_steps = five times the ramp's steps (the ~2,000-vertex valve settles in
// 2.3 times; docs/performance.md), rounded up to a thousand, and a note says so. Returns the
// cap written, or 0.
int fitStepCapToMesh(ValveCase& valve_case);

// A closure that failed: prints "error: <what>: <error><suffix>" ("simulation failed: " before
// the error for a divergence) and returns its exit code: kExitSimulationFailed for a
// divergence, kExitBadInput for any other error, which is the input's.
int reportClosureFailure(const SimulationResult& result, const std::string& what,
                         const std::string& suffix = "");

// The prolapse lines printed after a Table 1 row: what the tracings show, what the closed
// mesh shows in the tracing planes (Table 1's "Prolapse reconstructed" compares these two)
// and in its tissue (every vertex, open-state localisation; a diagnostic). `indent` prefixes
// each line. Without tracings only the tissue line. Then how much of the orifice the leaflets
// cover seen en face (orifice_coverage.h).
std::string closedValveSummary(const ValveMetrics& metrics, const std::string& indent = "");

// Multi-line human summary of a case (mesh, leaflets, annulus, tracings, tips, cords).
std::string caseSummary(const ValveCase& valve_case);

// "note: ..." lines for tracings that repeat an earlier one point for point (a file pasted
// twice): each point then counts twice in the fit, whose SDs come out narrower than the data
// warrant; "" when none does. validate and fit print it.
std::string duplicateTracingsNote(const ValveCase& valve_case);

}  // namespace chordfit::cli
