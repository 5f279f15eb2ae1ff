// chordfit: command-line entry. The only translation unit that includes CLI11 (slow headers);
// it fills the option structs of commands.h and dispatches.
#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>
#include <limits>
#include <optional>
#include <regex>
#include <string>
#include <vector>

#include <unistd.h>
#include <CLI/CLI.hpp>

#include "core/json_fields.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/integer_text.h"
#include "tools/revision.h"
#include "tools/staged_output.h"

namespace {

using namespace chordfit::cli;

// Integer options take an integral value in any decimal form ("1e3", "400.0", "+3", "007"), as
// the integer keys of a case's settings do (docs/case-format.md), always in base 10 (CLI11
// alone reads "077" as octal and takes "0x40"): tools/integer_text.h. Values beyond the
// option's type are refused here, naming the value as given (CLI11 would say "Could not
// convert", or wrap "-1" into an unsigned option); the option's own checks then see plain
// digits. `bounds`: the option's own range, checked here too, so that every wrong value is
// refused in one sentence ("must be an integer in [1, 64], got 2.5").
struct IntegerBounds {
  long long lowest, highest;
};

template <typename Integer>
CLI::Validator integralInAnyForm(std::optional<IntegerBounds> bounds) {
  const std::string lowest =
      bounds ? std::to_string(bounds->lowest) : std::to_string(std::numeric_limits<Integer>::min());
  const std::string highest = bounds ? std::to_string(bounds->highest)
                                     : std::to_string(std::numeric_limits<Integer>::max());
  return CLI::Validator(
      [bounded = bounds.has_value(), lowest, highest](std::string& value) {
        const std::optional<std::string> integer = canonicalInteger(value);
        const bool below = integer && compareIntegerTexts(*integer, lowest) < 0;
        const bool above = integer && compareIntegerTexts(*integer, highest) > 0;
        if (bounded && (!integer || below || above))
          return "must be an integer in [" + lowest + ", " + highest + "], got " + value;
        if (!integer) return "expected an integer, got '" + value + "'";
        if (below)
          return (lowest == "0" ? std::string("must be a non-negative integer")
                                : "must be at least " + lowest) +
                 ", got " + value;
        if (above) return "must be at most " + highest + ", got " + value;
        value = *integer;
        return std::string();
      },
      "");
}

template <typename Integer>
CLI::Option* addIntegerOption(CLI::App* cmd, const std::string& name, Integer& value,
                              const std::string& help,
                              std::optional<IntegerBounds> bounds = std::nullopt) {
  return cmd->add_option(name, value, help)->transform(integralInAnyForm<Integer>(bounds));
}

// --threads of every command, in [1, 64] (CLI::Range said "Value 2.5 not in range 1 to 64").
constexpr int kMaxThreads = 64;

// `what`: the closures the threads run, e.g. "the closure".
void addThreadsOption(CLI::App* cmd, int& threads, const std::string& what) {
  addIntegerOption(cmd, "--threads", threads,
                   "Threads for " + what + ", 1-64; the same result for any count",
                   IntegerBounds{1, kMaxThreads})
      ->capture_default_str();
}

// The cord and tissue files of the commands that close a case, in the same words everywhere.
constexpr const char* kCordsFileHelp =
    "Cord set file, CordSet JSON (default: the case's cords, else the heuristic's)";
constexpr const char* kTissueFileHelp =
    "Regional tissue JSON, one stiffness factor per vertex, e.g. a fit's tissue.json "
    "(default: the case's)";

void addValidate(CLI::App& app, ValidateOptions& o) {
  CLI::App* cmd = app.add_subcommand("validate", "Check a case directory and print its summary");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory (holds case.json)")->required();
}

void addMakeValve(CLI::App& app, MakeValveOptions& o) {
  CLI::App* cmd =
      app.add_subcommand("make-valve", "Write a parametric mitral valve case (open state)");
  cmd->add_option("--out", o.out_dir, "Output directory: the case")->required();
  chordfit::ValveParameters& p = o.parameters;
  cmd->add_option("--edge", p.target_edge_mm, "Target edge length, mm, in [0.2, 10]")
      ->capture_default_str();
  cmd->add_option("--annulus", o.annulus_file,
                  "Annulus polyline to use instead of the parametric saddle (then --ap and --cc "
                  "do not act): plain JSON point list, Slicer markups .mrk.json, or delimited "
                  "text .csv, .fcsv, .txt; mm (spanning 2-150 mm), anterior at +x, atrium at +z");
  cmd->add_option("--name", o.name, "Case name (printable characters, not blank)")
      ->capture_default_str();
  cmd->add_option("--ap", p.ap_diameter_mm,
                  "Anteroposterior annulus diameter (open), mm, in (0, 100]")
      ->capture_default_str();
  cmd->add_option("--cc", p.cc_diameter_mm, "Commissural annulus diameter (open), mm, in (0, 100]")
      ->capture_default_str();
  cmd->add_option("--saddle", p.saddle_height_mm,
                  "Annulus saddle height (open), mm, at most half the smaller diameter (with "
                  "--annulus only the closed/open ratio acts)")
      ->capture_default_str();
  cmd->add_option("--closed-saddle", p.closed_saddle_height_mm,
                  "Saddle height (closed), mm, at most half the smaller diameter (with --annulus "
                  "only the closed/open ratio acts)")
      ->capture_default_str();
  cmd->add_option("--anterior-height", p.anterior_height_mm,
                  "A2 height, annulus to free edge, mm, > 0")
      ->capture_default_str();
  cmd->add_option("--posterior-height", p.posterior_height_mm, "P2 height, mm, > 0")
      ->capture_default_str();
  cmd->add_option("--posterior-side-height", p.posterior_side_height_mm,
                  "P1 and P3 heights, mm, > 0")
      ->capture_default_str();
  cmd->add_option("--commissural-height", p.commissural_height_mm,
                  "Leaflet height at the commissures, mm, > 0")
      ->capture_default_str();
  cmd->add_option("--indentation", p.indentation_depth,
                  "Depth of the P1/P2 and P2/P3 clefts, fraction of the scallop height, in "
                  "[0, 0.9]")
      ->capture_default_str();
}

void addHeuristic(CLI::App& app, HeuristicCommandOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "heuristic",
      "Build the paper's heuristic cord set (automatic cord placement if needed; the tips at the "
      "case's pm_tips, paired by order with the case's cords' tips when it has cords)");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory")->required();
  cmd->add_option("--out", o.out_file, "Output file: the cord set (CordSet JSON)")->required();
  cmd->add_option("--primary-spacing", o.primary_spacing_mm,
                  "Arc length between primary cords on the free edge, mm, at least 0.1")
      ->capture_default_str();
  cmd->add_option("--secondary-spacing", o.secondary_spacing_mm,
                  "Spacing of secondary cords on the belly, mm, at least 0.1")
      ->capture_default_str();
  cmd->add_option("--secondary-depth", o.secondary_depth_mm,
                  "Distance of secondary cords from the free edge, mm, > 0")
      ->capture_default_str();
  cmd->add_option("--primary-compliance", o.primary_compliance,
                  "Primary cords' compliance, mm/N, in [0, 10]; 0 = inextensible (the paper's); "
                  "only for the cords the heuristic places")
      ->capture_default_str();
  cmd->add_option("--secondary-compliance", o.secondary_compliance,
                  "Secondary cords' compliance, mm/N, in [0, 10]; 0 = inextensible (the "
                  "paper's); only for the cords the heuristic places")
      ->capture_default_str();
}

// --set KEY=VALUE, repeatable; one value per --set so that positionals may follow it.
void addSettingOverrides(CLI::App* cmd, std::vector<std::string>& overrides) {
  cmd->add_option("--set", overrides,
                  "Override a simulator setting of the case's \"simulation\" block for this run: "
                  "KEY=VALUE, e.g. youngs_modulus_mpa=2 (repeatable; docs/case-format.md, "
                  "\"Simulator overrides\")")
      ->allow_extra_args(false);
}

void addMetrics(CLI::App& app, MetricsOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "metrics", "Deviation to the tracings, area and prolapse of a closed mesh (Table 1 row)");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory")->required();
  cmd->add_option("--mesh", o.mesh_file, "Closed mesh (same topology as the case mesh)")
      ->required();
  cmd->add_option("--out", o.out_file, "Output file (optional): the metrics (metrics.json keys)");
  // The orifice coverage grows the leaflets by the settings' contact thickness: a mesh that
  // simulate closed with --set thickness_mm=2 is measured as it was closed only with the same.
  addSettingOverrides(cmd, o.settings_overrides);
}

void addSimulate(CLI::App& app, SimulateOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "simulate", "Close the valve with XPBD to equilibrium; write closed.ply/.vtk + metrics");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory")->required();
  cmd->add_option("--cords", o.cords_file, kCordsFileHelp);
  cmd->add_option("--tissue", o.tissue_file, kTissueFileHelp);
  cmd->add_option("--phase", o.phase,
                  "close, or open (close, then reverse the fields and open again)")
      ->capture_default_str();
  cmd->add_option("--out", o.out_dir,
                  "Output directory: closed.ply, closed.vtk, metrics.json, enface.svg, "
                  "sections.svg (opened.* with --phase open)")
      ->required();
  addThreadsOption(cmd, o.threads, "the closure");
  cmd->add_flag("--quiet", o.quiet, "No progress lines");
  addSettingOverrides(cmd, o.settings_overrides);
}

// The sweep's own range (sweep_command.cpp): scales 1 +- range stay well above 0, and a window
// wider than the largest sweep (2,001 scales) could never be filled.
void addSweepCord(CLI::App& app, SweepCordOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "sweep-cord", "Scan one cord's rest-length scale; measure the forward map's smoothness");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory")->required();
  cmd->add_option("--cords", o.cords_file, kCordsFileHelp);
  cmd->add_option("--tissue", o.tissue_file, kTissueFileHelp);
  addIntegerOption(cmd, "--cord", o.cord,
                   "Cord index, 0 to the set's cords - 1 (default: the P2 primary cord nearest "
                   "P2's centre)")
      ->check(CLI::Validator(
          [](const std::string& value) {
            return value.empty() || value[0] == '-' ? "must be a cord index >= 0, got " + value
                                                    : std::string();
          },
          ""));
  cmd->add_option("--range", o.range,
                  "Scan scales 1 + k step over [1 - range, 1 + range]; range in (0, 0.5)")
      ->capture_default_str();
  cmd->add_option("--step", o.step, "Scale step, in (0, range]")->capture_default_str();
  addIntegerOption(cmd, "--window", o.window,
                   "Half-width of the local quadratic fit, points, in [2, 1000]")
      ->capture_default_str();
  addThreadsOption(cmd, o.threads, "the sweep's closures (run in parallel)");
  cmd->add_option("--out", o.out_dir, "Output directory: sweep.csv, sweep.svg, sweep.json")
      ->required();
  cmd->add_flag("--quiet", o.quiet, "No progress lines");
  addSettingOverrides(cmd, o.settings_overrides);
}

void addMakeCase(CLI::App& app, MakeCaseOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "make-case", "Write a synthetic case with known truth (cohort preset; truth in DIR/truth)");
  // Not ->required(): --list needs neither; runMakeCase asks for them otherwise.
  cmd->add_option("--preset", o.preset, "Cohort preset (see --list); required unless --list");
  cmd->add_option("--out", o.out_dir,
                  "Output directory: the case, its truth in truth/; required unless --list");
  // Unsigned: "-1" is refused, not wrapped to 2^64 - 1, and a value past 2^64 - 1 is refused,
  // not saturated (seed 99999999999999999999 made the case of seed 18446744073709551615).
  addIntegerOption(cmd, "--seed", o.seed, "Patient seed (same seed => identical files)")
      ->capture_default_str();
  addIntegerOption(cmd, "--planes", o.planes, "Long-axis tracing planes, in [1, 36]")
      ->capture_default_str();
  cmd->add_option("--noise", o.noise_mm, "Tracing noise SD, mm (in-plane), in [0, 5]")
      ->capture_default_str();
  cmd->add_option("--dropout", o.dropout,
                  "Fraction of the traced length lost to dropout, in [0, 0.9]")
      ->capture_default_str();
  cmd->add_option("--edge", o.edge_mm, "Case mesh edge length, mm, in [1, 5] (truth: edge / 2)")
      ->capture_default_str();
  addThreadsOption(cmd, o.threads, "the truth closure");
  cmd->add_flag("--attach-at-vertices", o.attach_at_vertices,
                "Cords insert at the vertex nearest their anatomical point on each mesh (up to "
                "half an edge off it; the cohort before point attachments) instead of at the "
                "point");
  cmd->add_flag("--list", o.list, "List the presets and what each models");
  cmd->add_flag("--quiet", o.quiet, "No progress lines");
}

void addCompare(CLI::App& app, CompareOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "compare", "Close the case once per cord set; Table 1 side by side (manual vs optimised)");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory")->required();
  cmd->add_option("CORDS", o.cords_files, "CordSet JSON files (one or more)")->required();
  cmd->add_option("--labels", o.labels,
                  "Row labels, comma-separated, one per CORDS file (default: the file names)");
  cmd->add_option("--tissues", o.tissues,
                  "Regional tissue files, comma-separated, one per CORDS file ('-': the case's "
                  "own), e.g. a tissue-prefit fit's tissue.json");
  addThreadsOption(cmd, o.threads, "the cord sets' closures (run in parallel)");
  cmd->add_option("--out", o.out_dir,
                  "Output directory (optional): compare.md, compare.csv, cords.csv (each cord's "
                  "length per set), sections.svg, enface_K.svg (one per cord set)");
  cmd->add_flag("--quiet", o.quiet, "No progress lines");
  addSettingOverrides(cmd, o.settings_overrides);
}

void addImportMesh(CLI::App& app, ImportMeshOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "import-mesh",
      "Make a case from a segmented open valve mesh and 3 landmarks (ring, leaflets derived)");
  cmd->add_option("MESH", o.mesh_file, "Open-state valve mesh (.ply .obj .stl .off .vtk)")
      ->required();
  cmd->add_option("--landmarks", o.landmarks_file,
                  "Curve file with 3 points: anterolateral commissure, posteromedial "
                  "commissure, a point of the anterior annulus")
      ->required();
  cmd->add_option("--closed-annulus", o.closed_annulus_file,
                  "Curve file: the closed-state (systolic) annulus as a loop (without it the "
                  "annulus stays where it is open)");
  cmd->add_option(
      "--tracings", o.tracings_file,
      "Tracings of the closed valve (tracings.json format; their points are written into the "
      "case's tracings.json)");
  cmd->add_option("--pm-tips", o.pm_tips_file,
                  "Curve file with the papillary-muscle tips, anterolateral first (default: "
                  "the heuristic places them)");
  cmd->add_option("--name", o.name,
                  "Case name, printable characters (default: the output directory's name)");
  cmd->add_flag("--keep-seams", o.keep_seams,
                "Keep vertices at the same position apart (default: welded into one sheet; "
                "for a seam the mesh leaves open on purpose)");
  cmd->add_option("--out", o.out_dir,
                  "Output directory: the case (an earlier chordfit case there is replaced; a "
                  "file of yours the case would replace is refused)")
      ->required();
}

void addEditCords(CLI::App& app, EditCordsOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "edit-cords",
      "Scale and lock cords as the paper's editor does (rest = seed rest length x scale)");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory")->required();
  cmd->add_option("--cords", o.cords_file, kCordsFileHelp);
  cmd->add_option("--out", o.out_file, "Output file: the edited cord set (CordSet JSON)")
      ->required();
  cmd->add_option("--all", o.all_scale, "Scale every cord by S; every scale S is in (0, 10]")
      ->type_name("S");
  cmd->add_option("--group", o.group_scales,
                  "Scale a leaflet/tip group: NAME=S, e.g. posterior/posteromedial=0.9 "
                  "(repeatable, each group once)");
  cmd->add_option("--segment", o.segment_scales,
                  "Scale the cords of a Carpentier segment: SEG=S, e.g. P2=1.2 (repeatable, each "
                  "segment once)");
  cmd->add_option("--cord", o.cord_scales,
                  "Scale cords by index: K=S, K,K=S or all=S (repeatable, each cord once)");
  cmd->add_option("--move-tip", o.tip_moves,
                  "Move a PM tip: NAME=DX,DY,DZ in mm, e.g. anterolateral=0,0,-2 (repeatable, "
                  "each tip once)");
  cmd->add_option("--lock", o.lock,
                  "Lock cords after the scaling: K,K,... | edited | all (fit keeps them)");
  cmd->add_option("--unlock", o.unlock, "Unlock cords before the scaling: K,K,... | all");
}

void addFit(CLI::App& app, FitCommandOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "fit", "Fit cord rest lengths (and PM tips) to the tracings with Ceres or NLopt");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory")->required();
  cmd->add_option("--seed-cords", o.seed_cords_file,
                  "Seed cord set file, CordSet JSON (default: the case's cords, else the "
                  "heuristic's); manual cords are the start, locked cords are kept");
  cmd->add_option("--params", o.params, "scales | groups | scales+tips")->capture_default_str();
  cmd->add_option("--optimizer", o.optimizer, "ceres | bobyqa | cobyla | sbplx | crs2")
      ->capture_default_str();
  addIntegerOption(cmd, "--max-sims", o.max_sims,
                   "Forward closures of the fit (budget; the written result adds one, and the "
                   "uncertainty and locked-cord probe after the fit run theirs outside it)")
      ->capture_default_str();
  addThreadsOption(cmd, o.threads, "the fit's closures (finite differences, pre-fit grids)");
  cmd->add_option("--scale-bounds", o.scale_bounds, "Lower and upper bound on a scale, 0 < LO < HI")
      // (1, 2), not 2: the help then shows "LO,HI=0.7,1.5" without CLI11's " x 2"; a single
      // number is refused by runFit, naming it.
      ->expected(1, 2)
      ->delimiter(',')
      ->type_name("LO,HI")
      ->default_str("0.7,1.5");
  cmd->add_option("--tip-box", o.tip_box_mm,
                  "PM tip offset bound per axis, mm (scales+tips); at most the case's reach / "
                  "sqrt(3): 28.8 mm for a valve within 50 mm (reach: the larger of 50 mm and the "
                  "mesh's span)")
      ->capture_default_str();
  cmd->add_option("--tip-weight", o.tip_weight,
                  "Prior on the PM tip offsets (scales+tips): mm of residual per mm of offset, "
                  "per coordinate, in [0, 1000] (docs/fitting.md, \"Regularisation\")")
      ->capture_default_str();
  cmd->add_flag_callback(
      "--no-prefit", [&o] { o.prefit = false; },
      "Skip the cord pre-fits (a global scale factor, one per cord kind, then per-segment "
      "scales)");
  cmd->add_flag("--tissue-prefit", o.tissue_prefit,
                "Also try softer tissue per segment (0.3, 0.1, 0.05 of the modulus) before the "
                "optimiser; tissue.json is written when the tissue changes (by it or by the "
                "tissue retry)");
  cmd->add_flag_callback(
      "--no-tissue-retry", [&o] { o.tissue_retry = false; },
      "When the fitted closure misses a prolapse the tracings show, do not fit again with the "
      "tissue pre-fit (the retry, within --max-sims, is kept only if it fits the tracings "
      "better)");
  cmd->add_flag_callback(
      "--no-slack-release", [&o] { o.slack_release = false; },
      "Keep slack cords where the optimiser left them instead of raising them to the "
      "valve's typical scale of their kind (the median of its taut cords)");
  cmd->add_option("--fd-step", o.fd_scale_step,
                  "Central-difference step on a scale, at least 1e-6 and below LO")
      ->capture_default_str();
  cmd->add_option("--fd-tip-step", o.fd_tip_step_mm,
                  "Central-difference step on a tip, mm, in [1e-4, 5]")
      ->capture_default_str();
  cmd->add_flag("--fd-warm", o.fd_warm_start,
                "Warm-start finite-difference closures from the base closed state");
  cmd->add_flag("--fd-slack-closures", o.fd_slack_closures,
                "Run the difference closures of parameters that move only slack cords too "
                "(default: their column is 0, exactly, without closures)");
  cmd->add_option("--distance", o.distance,
                  "Data residual per tracing point: own-leaflet (distance to the surface of the "
                  "point's labelled leaflet) | surface (to the whole closed mesh, as AvgD)")
      ->capture_default_str();
  cmd->add_option("--section-weight", o.section_weight,
                  "Weight of the section residuals: closed-mesh sections farther than 1.5 mm "
                  "from the tracings of their plane, in [0, 1000] (0: off; docs/fitting.md)")
      ->capture_default_str();
  cmd->add_flag_callback(
      "--no-uncertainty", [&o] { o.uncertainty = false; },
      "Skip the diagnostics after the fit: the per-parameter uncertainty (uncertainty.csv; up "
      "to 2 closures per parameter) and the locked-cord probe (report.md; 3 closures per "
      "taut locked cord)");
  cmd->add_option("--out", o.out_dir,
                  "Output directory: cords.json, closed.ply/.vtk, metrics.json, report.md and "
                  "the figures (docs/outputs.md)")
      ->required();
  cmd->add_flag("--quiet", o.quiet, "No progress lines");
  addSettingOverrides(cmd, o.settings_overrides);
}

}  // namespace

namespace {

// Ctrl-C or a kill mid-run used to end without a word. Say so, then die of the signal as
// before (exit status 128 + signal: 130, 143), which scripts and shells recognise. Every
// command writes its results only when it finishes (staged, then renamed in), so an
// interrupted run leaves no half-written output; only async-signal-safe calls here.
extern "C" void reportInterruption(int signal_number) {
  static const char message[] =
      "\nchordfit: interrupted; outputs are written only when a command finishes\n";
  [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, message, sizeof message - 1);
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

// The first word, when it is neither a command nor an option of the program: CLI11 reads an
// unknown word as a stray argument and an unknown option as nothing at all, and says only
// that a subcommand is required. Names the word (and the commands, or the option meant) and
// returns true.
bool refuseUnknownFirstWord(CLI::App& app, const std::string& word) {
  if (word.empty() || word == "-") return false;
  if (word[0] != '-') {
    std::string commands;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
      known |= sub->get_name() == word;
      commands += (commands.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known)
      std::cerr << "error: \"" << word << "\" is not a chordfit command (" << commands
                << "; chordfit --help)\n";
    return !known;
  }
  const std::string name = word.substr(0, word.find('='));
  std::vector<std::string> options;
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& lname : option->get_lnames()) options.push_back("--" + lname);
    for (const std::string& sname : option->get_snames()) options.push_back("-" + sname);
  }
  if (std::find(options.begin(), options.end(), name) != options.end()) return false;
  std::cerr << "error: unknown option " << name
            << " (chordfit takes --help and --version before a command; chordfit --help)\n";
  if (const std::string hint = chordfit::typoSuggestion(name, options); !hint.empty())
    std::cerr << "  " << name << ": " << hint.substr(2) << "\n";
  return true;
}

// The option of `command` (of the program when "") called `name`, or nullptr.
const CLI::Option* findOption(CLI::App& app, const std::string& command, const std::string& name) {
  const CLI::App* scope = command.empty() ? &app : app.get_subcommand(command);
  for (const CLI::Option* option : scope->get_options())
    if (option->check_name(name) || option->get_name() == name) return option;
  return nullptr;
}

// What a value of `option` must be, in words, from the type its help shows.
std::string expectedValue(const CLI::Option* option) {
  const std::string type = option == nullptr ? "" : option->get_type_name();
  if (option != nullptr && option->get_items_expected_max() == 2) return "two numbers " + type;
  if (type.rfind("FLOAT", 0) == 0) return "a number";
  if (type.rfind("UINT", 0) == 0) return "a non-negative integer";
  if (type.rfind("INT", 0) == 0) return "an integer";
  return type.empty() ? "another value" : type;
}

// CLI11's own wording of the common usage errors, in the words of the commands' checks:
// "Could not convert: --edge = abc" -> "--edge: expected a number, got 'abc'". Others as
// CLI11 says them.
std::string plainParseMessage(CLI::App& app, const std::string& command,
                              const CLI::ParseError& error,
                              const std::vector<std::string>& arguments) {
  const std::string what = error.what();
  std::smatch match;
  if (dynamic_cast<const CLI::ConversionError*>(&error) != nullptr &&
      std::regex_match(what, match, std::regex("Could not convert: (.+?) = (.*)"))) {
    const std::string name = match[1], value = match[2];
    const CLI::Option* option = findOption(app, command, name);
    return name + ": expected " + expectedValue(option) + ", got '" + value + "'";
  }
  // The count of values CLI11 received: "--edge 2 --edge 3" gives 2 where 1 is taken,
  // "--scale-bounds 0.5" 1 where 2 are.
  auto countMessage = [&](const std::string& name, int received) {
    // "--scale-bounds 0.5,1.2,0.6,1.3" is given once with 4 values: count the option itself.
    const long given = std::count_if(arguments.begin(), arguments.end(), [&](const std::string& a) {
      return a == name || a.rfind(name + "=", 0) == 0;
    });
    if (given > 1) return name + ": given " + std::to_string(given) + " times; give it once";
    return name + ": expected " + expectedValue(findOption(app, command, name)) + ", got " +
           std::to_string(received) + (received == 1 ? " value" : " values");
  };
  if (std::regex_match(what, match,
                       std::regex("(.+): At (Most|least) ([0-9]+) required but received ([0-9]+)")))
    return countMessage(match[1], std::stoi(match[4]));
  if (std::regex_match(what, match,
                       std::regex("Expected exactly ([0-9]+) arguments to (.+), got ([0-9]+)")))
    return countMessage(match[2], std::stoi(match[3]));
  if (std::regex_match(what, match, std::regex("(.+) is required")) && match[1] != "A subcommand")
    return std::string(match[1]) + ": required";
  if (dynamic_cast<const CLI::ExtrasError*>(&error) != nullptr) {
    const CLI::App* scope = command.empty() ? &app : app.get_subcommand(command);
    std::vector<std::string> words = scope->remaining();
    if (words.empty()) words = app.remaining();
    if (words.empty()) return what;
    if (words.size() == 1) return "unexpected argument \"" + words.front() + "\"";
    std::string listed;
    for (const std::string& word : words) listed += " " + word;
    return "unexpected arguments:" + listed;
  }
  if (what == "A subcommand is required") return "a command is required";
  return what;
}

// After an unexpected argument: the option meant by a mistyped one ("--max-sim"), and for
// make-case the --preset a bare preset name was meant for.
void printStrayArgumentHints(CLI::App& app, const std::string& command, int argc, char** argv) {
  std::vector<std::string> known;
  for (const CLI::Option* option : app.get_subcommand(command)->get_options())
    for (const std::string& name : option->get_lnames()) known.push_back("--" + name);
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (command == "make-case" && isPresetName(arg) &&
        (i == 2 || std::string(argv[i - 1]) != "--preset"))
      std::cerr << "  " << arg << ": a preset; did you mean \"--preset " << arg << "\"?\n";
    if (arg.rfind("--", 0) != 0 || std::find(known.begin(), known.end(), arg) != known.end())
      continue;
    const std::string hint = chordfit::typoSuggestion(arg, known);
    if (!hint.empty()) std::cerr << "  " << arg << ": " << hint.substr(2) << "\n";
  }
}

// The options of `cmd` given on the command line (their long names), for the commands' notes
// on options that do not act.
std::vector<std::string> givenOptions(const CLI::App* cmd) {
  std::vector<std::string> given;
  for (const CLI::Option* option : cmd->get_options())
    if (option->count() > 0 && !option->get_lnames().empty())
      given.push_back("--" + option->get_lnames().front());
  return given;
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGINT, reportInterruption);
  std::signal(SIGTERM, reportInterruption);
  CLI::App app{"chordfit: chordae tendineae fitting for mitral valve closure simulation"};
  app.require_subcommand(1);
  // "chordfit 0.1.0 (revision 433c786)": the benchmark records the revision of the binary
  // that ran each job from this line.
  app.set_version_flag("--version",
                       std::string("chordfit 0.1.0 (revision ") + sourceRevision() + ")");
  ValidateOptions validate;
  MakeValveOptions make_valve;
  ImportMeshOptions import_mesh;
  HeuristicCommandOptions heuristic;
  MetricsOptions metrics;
  SimulateOptions simulate;
  MakeCaseOptions make_case;
  addValidate(app, validate);
  addMakeValve(app, make_valve);
  addImportMesh(app, import_mesh);
  addHeuristic(app, heuristic);
  EditCordsOptions edit_cords;
  addEditCords(app, edit_cords);
  addMetrics(app, metrics);
  addSimulate(app, simulate);
  SweepCordOptions sweep_cord;
  addSweepCord(app, sweep_cord);
  addMakeCase(app, make_case);
  FitCommandOptions fit;
  addFit(app, fit);
  CompareOptions compare;
  addCompare(app, compare);
  if (argc > 1 && refuseUnknownFirstWord(app, argv[1])) return kExitBadInput;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help is a "parse error" with exit code 0: CLI11 prints the help.
    if (e.get_exit_code() == 0) return app.exit(e) == 0 ? kExitOk : kExitBadInput;
    // Every other usage error in the form of the commands' own checks: "error: COMMAND: ...".
    const std::string command = argc > 1 && argv[1][0] != '-' ? argv[1] : "";
    std::cerr << "error: " << (command.empty() ? "" : command + ": ")
              << plainParseMessage(app, command, e, std::vector<std::string>(argv, argv + argc))
              << " (chordfit " << (command.empty() ? "" : command + " ") << "--help)\n";
    if (!command.empty() && dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr)
      printStrayArgumentHints(app, command, argc, argv);
    return kExitBadInput;
  }
  fit.given_options = givenOptions(app.get_subcommand("fit"));
  make_valve.given_options = givenOptions(app.get_subcommand("make-valve"));
  // Before any work: an output place that cannot be written is a usage error (exit 2). A
  // directory the command writes into, or a file it writes; metrics and compare write only
  // when given --out.
  // A directory's `files`: what the command writes there, none of which may be a directory;
  // `inputs`: what the run reads, none of which an output may replace. (A cord file output
  // may replace the cords it read: edit-cords editing a cord file in place is an edit.)
  struct OutputPlace {
    const char* command;
    std::string path;
    bool is_file;
    std::vector<std::string> files;
    std::vector<std::string> inputs;
  };
  auto withCase = [](const std::string& case_dir, std::vector<std::string> inputs) {
    for (std::string& file : caseInputFiles(case_dir)) inputs.push_back(std::move(file));
    return inputs;
  };
  const OutputPlace places[] = {
      {"make-valve", make_valve.out_dir, false, makeValveOutputFiles(), {make_valve.annulus_file}},
      {"import-mesh",
       import_mesh.out_dir,
       false,
       importMeshOutputFiles(),
       {import_mesh.mesh_file, import_mesh.landmarks_file, import_mesh.closed_annulus_file,
        import_mesh.tracings_file, import_mesh.pm_tips_file}},
      // heuristic and edit-cords may replace the case's cords file (regenerating or editing
      // them is what they are for), none of its other files.
      {"heuristic", heuristic.out_file, true, {}, caseInputFiles(heuristic.case_dir, false)},
      {"edit-cords", edit_cords.out_file, true, {}, caseInputFiles(edit_cords.case_dir, false)},
      {"metrics", metrics.out_file, true, {}, withCase(metrics.case_dir, {metrics.mesh_file})},
      {"simulate", simulate.out_dir, false, simulateOutputFiles(simulate),
       withCase(simulate.case_dir, {simulate.cords_file, simulate.tissue_file})},
      {"sweep-cord", sweep_cord.out_dir, false, sweepCordOutputFiles(),
       withCase(sweep_cord.case_dir, {sweep_cord.cords_file})},
      {"make-case", make_case.out_dir, false, makeCaseOutputFiles(), {}},
      {"fit", fit.out_dir, false, fitOutputFiles(), withCase(fit.case_dir, {fit.seed_cords_file})},
      {"compare", compare.out_dir, false, compareOutputFiles(compare),
       withCase(compare.case_dir, compareInputFiles(compare))}};
  for (const OutputPlace& place : places) {
    // Whether --out was given, not whether it is empty: an empty one is refused, not skipped
    // (make-case reports a missing --out itself; --list needs none).
    if (!app.got_subcommand(place.command) ||
        app.get_subcommand(place.command)->count("--out") == 0)
      continue;
    const bool usable =
        place.is_file ? outputFileUsable(place.command, place.path) &&
                            outputSparesInputs(place.command, place.path, place.inputs)
                      : outputDirectoryUsable(place.command, place.path, place.files, place.inputs);
    if (!usable) return kExitBadInput;
  }
  // An empty list is one the user gave, not an option left out ("--lock ''" read "nothing to
  // do" when alone and was ignored beside others).
  if (app.got_subcommand("edit-cords")) {
    for (const auto& [option, list] :
         {std::pair{"--lock", &edit_cords.lock}, std::pair{"--unlock", &edit_cords.unlock}})
      if (app.get_subcommand("edit-cords")->count(option) > 0 && list->empty()) {
        std::cerr << "error: edit-cords: " << option
                  << ": empty; expected cord indices K,K,..., \"all\""
                  << (std::string(option) == "--lock" ? " or \"edited\"" : "") << "\n";
        return kExitBadInput;
      }
  }
  try {
    if (app.got_subcommand("validate")) return runValidate(validate);
    if (app.got_subcommand("make-valve")) return runMakeValve(make_valve);
    if (app.got_subcommand("import-mesh")) return runImportMesh(import_mesh);
    if (app.got_subcommand("heuristic")) return runHeuristic(heuristic);
    if (app.got_subcommand("metrics")) return runMetrics(metrics);
    if (app.got_subcommand("simulate")) return runSimulate(simulate);
    if (app.got_subcommand("sweep-cord")) return runSweepCord(sweep_cord);
    if (app.got_subcommand("make-case")) return runMakeCase(make_case);
    if (app.got_subcommand("fit")) return runFit(fit);
    if (app.got_subcommand("compare")) return runCompare(compare);
    if (app.got_subcommand("edit-cords")) return runEditCords(edit_cords);
  } catch (const std::exception& e) {
    std::cerr << "error: " << chordfit::cli::withoutStagingDirectories(e.what()) << "\n";
    return kExitFailure;
  }
  return kExitBadInput;
}
