#include "tools/command_support.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <limits>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/case_extent.h"
#include "core/case_io.h"
#include "core/closure_model.h"
#include "core/cordset_io.h"
#include "core/counted.h"
#include "core/heuristic.h"
#include "core/leaflet_agreement.h"
#include "core/mesh_topology.h"
#include "core/metrics.h"
#include "core/synthetic_case.h"
#include "tools/commands.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

namespace {

// Boundary loops besides the annulus ring and the free edge: holes in the leaflet surface or
// loose pieces. import-mesh warned of them, validate and the others took such a case silently
// (each hole's rim is simulated as a free edge, and the labels near it may be off).
int meshHoles(const ValveMesh& mesh) {
  return holesBeyondRingAndFreeEdge(boundaryLoops(mesh.F).size());
}

}  // namespace

std::optional<ValveCase> loadCaseOrReport(const std::string& case_dir) {
  static std::set<std::string> warned_cases;
  static std::set<std::string> warned_holes;
  Diagnostics diagnostics;
  std::optional<ValveCase> loaded = loadCase(case_dir, diagnostics);
  if (!loaded) {
    // Problems inside the case name files relative to it; say which case they belong to.
    std::cerr << "case " << case_dir << ": " << diagnostics.problems().size() << " problem(s)\n";
    diagnostics.print(std::cerr);
  } else if (const double agreement = tracingLeafletAgreement(loaded->mesh, loaded->tracings);
             agreement < kLeafletAgreementLow && warned_cases.insert(case_dir).second) {
    // Not an error: a valve traced in an unusual frame may still be right, and the user
    // decides; but every later number depends on it, so say it first (once per run: fit
    // reads the case again for its fitted closure).
    printWarning(
        "case %s: only %ld %% of the tracing points lie nearest an open-state vertex of their "
        "own leaflet (65-80 %% on correctly labelled valves): are the leaflet labels (case.json "
        "leaflets.labels) or the tracings' leaflets swapped? Each point is measured to its own "
        "leaflet, so swapped labels make every distance, and a fit, wrong\n",
        case_dir.c_str(), std::lround(100.0 * agreement));
  }
  if (loaded && warned_holes.insert(case_dir).second) {
    if (const int holes = meshHoles(loaded->mesh); holes > 0)
      printWarning(
          "case %s: the valve mesh has %d boundary loop%s besides the annulus ring and the free "
          "edge: holes in the leaflet surface (a missing triangle?) or loose pieces; each such "
          "rim is simulated as a free edge\n",
          case_dir.c_str(), holes, holes == 1 ? "" : "s");
  }
  return loaded;
}

int reportProblems(const Diagnostics& diagnostics) {
  diagnostics.print(std::cerr);
  return kExitBadInput;
}

namespace {
void printToStderr(const char* prefix, const char* format, va_list arguments) {
  std::fflush(stdout);
  std::fputs(prefix, stderr);
  std::vfprintf(stderr, format, arguments);
}
}  // namespace

void printNote(const char* format, ...) {
  va_list arguments;
  va_start(arguments, format);
  printToStderr("note: ", format, arguments);
  va_end(arguments);
}

void printWarning(const char* format, ...) {
  va_list arguments;
  va_start(arguments, format);
  printToStderr("warning: ", format, arguments);
  va_end(arguments);
}

void printLinesToStderr(const std::string& lines) {
  if (lines.empty()) return;
  std::fflush(stdout);
  std::fputs(lines.c_str(), stderr);
}

std::string tissueBesideCordsNote(const char* command, const std::string& cords_file,
                                  const std::string& option) {
  if (cords_file.empty()) return "";
  const std::filesystem::path tissue =
      std::filesystem::path(cords_file).parent_path() / "tissue.json";
  std::error_code error;
  if (!std::filesystem::is_regular_file(tissue, error)) return "";
  return std::string("note: ") + command + ": " + tissue.string() + " lies beside " + cords_file +
         ": the fit that wrote them closed these cords on that tissue; this run closes them on "
         "the case's own (" +
         option + " to use it)\n";
}

bool optionFileFoundOrReport(const std::string& given_as, const std::string& file) {
  std::error_code error;
  if (std::filesystem::exists(file, error) || error) return true;
  std::cerr << "error: " << given_as << ": " << file << ": file not found\n";
  return false;
}

std::optional<CordSet> resolveCords(const ValveCase& valve_case, const std::string& cords_file,
                                    const std::string& given_as) {
  if (cords_file.empty()) {
    if (valve_case.cords) return valve_case.cords;
    return heuristicCordSet(valve_case);
  }
  if (!given_as.empty() && !optionFileFoundOrReport(given_as, cords_file)) return std::nullopt;
  Diagnostics diagnostics;
  CordSet set;
  if (!readCordSet(cords_file, cords_file, set, diagnostics) ||
      !checkCordVertices(set, valve_case.mesh, cords_file, diagnostics) ||
      !checkTipPlacement(valve_case.mesh, set.tips, cords_file, diagnostics)) {
    diagnostics.print(std::cerr);
    return std::nullopt;
  }
  return set;
}

std::string noCordsProblem(const ValveCase& valve_case, const std::string& case_dir,
                           const std::string& cords_file, const char* option) {
  if (!cords_file.empty()) return cords_file + " has no cords";
  if (valve_case.cords)
    return case_dir + ": the case's cord set has no cords (give " + option + ")";
  return case_dir + ": the heuristic placed no cords on this mesh";
}

std::optional<CaseWithCords> loadCaseWithCords(const char* command, const std::string& case_dir,
                                               const std::string& tissue_file,
                                               const std::string& cords_file) {
  auto valve_case = loadCaseOrReport(case_dir);
  if (!valve_case) return std::nullopt;
  if (!tissue_file.empty()) {
    if (!optionFileFoundOrReport(std::string(command) + ": --tissue", tissue_file))
      return std::nullopt;
    Diagnostics diagnostics;
    if (!loadTissueFile(tissue_file, tissue_file, *valve_case, diagnostics)) {
      reportProblems(diagnostics);
      return std::nullopt;
    }
  }
  auto cords = resolveCords(*valve_case, cords_file, std::string(command) + ": --cords");
  if (!cords) return std::nullopt;
  if (tissue_file.empty())
    printLinesToStderr(tissueBesideCordsNote(command, cords_file, "--tissue FILE"));
  return CaseWithCords{std::move(*valve_case), std::move(*cords)};
}

namespace {

// The time step a closure of the case takes with `settings` (the cords do not change it), or
// 0 when the case gives no simulation model (reported elsewhere).
double caseTimeStepMs(const ValveCase& valve_case, const SimulationSettings& settings) {
  SimulationModel model;
  std::string error;
  if (!closureModel(valve_case, CordSet{}, ClosurePhase::kClose, model, error)) return 0.0;
  return closureTimeStepMs(model, settings);
}

// Why the pressure ramp does not fit under the step cap at the automatic time step, which
// only the mesh gives (settingsFromJson checks a given dt_ms), or "".
std::string stepCapProblem(const ValveCase& valve_case, const SimulationSettings& settings) {
  if (settings.dt_ms != 0.0) return "";
  return rampBeyondStepCap(settings, caseTimeStepMs(valve_case, settings));
}

// A step cap that leaves a closure time to settle after a ramp of `ramp_steps` steps: five
// times the ramp, rounded up to the next 1,000 (what make-valve writes for a fine mesh);
// nullopt beyond the 1e8 steps the settings accept, where it would also overflow an int.
std::optional<int> stepCapForRamp(double ramp_steps) {
  if (!(5.0 * ramp_steps <= 1e8)) return std::nullopt;
  return static_cast<int>(std::ceil(5.0 * ramp_steps / 1000.0)) * 1000;
}

// The case without its regional tissue: the step the mesh alone gives.
ValveCase withUniformTissue(const ValveCase& valve_case) {
  ValveCase uniform = valve_case;
  uniform.tissue_stiffness.resize(0);
  return uniform;
}

// The step-cap problem when the tissue's stiffness factors are what shortened the automatic
// step (the case with uniform tissue fits its ramp under the cap): the factors, the step with
// and without them, and the two ways out. `takes_set`: the command has --set.
std::string tissueStepCapProblem(const ValveCase& valve_case, const SimulationSettings& settings,
                                 bool takes_set) {
  const double dt = caseTimeStepMs(valve_case, settings);
  const double uniform_dt = caseTimeStepMs(withUniformTissue(valve_case), settings);
  const double ramp_steps = std::ceil(settings.ramp_ms / dt);
  const std::optional<int> cap = stepCapForRamp(ramp_steps);
  char what[480];
  if (!cap) {
    std::snprintf(what, sizeof what,
                  "factors up to %g shorten the automatic time step to %.4g ms (%.4g ms with "
                  "uniform tissue): the %g ms pressure ramp takes %.3g steps, more than any step "
                  "cap a closure is allowed (1e8); give softer factors",
                  valve_case.tissue_stiffness.maxCoeff(), dt, uniform_dt, settings.ramp_ms,
                  ramp_steps);
    return what;
  }
  const std::string set_hint = takes_set ? "--set max_steps=" + std::to_string(*cap) + ", or " : "";
  std::snprintf(what, sizeof what,
                "factors up to %g shorten the automatic time step to %.4g ms (%.4g ms with "
                "uniform tissue): the %g ms pressure ramp takes %.0f steps, more than "
                "simulation.max_steps = %d; raise it (%s\"max_steps\": %d in case.json's "
                "simulation block) or give softer factors",
                valve_case.tissue_stiffness.maxCoeff(), dt, uniform_dt, settings.ramp_ms,
                ramp_steps, settings.max_steps, set_hint.c_str(), *cap);
  return what;
}

// Reports `problem`, a pressure ramp beyond the step cap of `settings` (`own`: the case's,
// before the overrides), at what made it so, checked in this order (each check builds the
// closure's model, so only once the cap is known to be short): the case's mesh and settings
// (case.json's simulation.max_steps), then the tissue's stiffness factors, whose stiffer tissue
// shortens the automatic step (`tissue_file`'s "stiffness" when given, else case.json's
// tissue_stiffness), then the overrides (`overrides_source`, "<command>: --set"). Blamed on
// case.json, a stiff tissue file named a simulation block that was not there.
void reportStepCapProblem(const std::string& problem, const ValveCase& valve_case,
                          const SimulationSettings& own, const SimulationSettings& settings,
                          const std::string& overrides_source, bool takes_set,
                          const std::string& tissue_file, Diagnostics& diagnostics) {
  const ValveCase uniform = withUniformTissue(valve_case);
  const bool has_tissue = valve_case.tissue_stiffness.size() > 0;
  if (!stepCapProblem(uniform, own).empty()) {
    diagnostics.error("case.json", "simulation.max_steps", problem);
  } else if (has_tissue && stepCapProblem(uniform, settings).empty()) {
    diagnostics.error(tissue_file.empty() ? "case.json" : tissue_file,
                      tissue_file.empty() ? "tissue_stiffness" : "stiffness",
                      tissueStepCapProblem(valve_case, settings, takes_set));
  } else {
    diagnostics.error(overrides_source, "simulation.max_steps", problem);
  }
}

// The `--set` items as one JSON object; on a malformed item prints it and returns nullopt.
std::optional<nlohmann::json> settingOverridesOrReport(const char* command,
                                                       const std::vector<std::string>& overrides) {
  nlohmann::json object = nlohmann::json::object();
  for (const std::string& item : overrides) {
    const size_t equals = item.find('=');
    const std::string key = item.substr(0, equals);
    const std::string value = equals == std::string::npos ? "" : item.substr(equals + 1);
    std::string problem;
    if (equals == std::string::npos || equals == 0 || value.empty())
      problem = "expected KEY=VALUE, e.g. youngs_modulus_mpa=2, got \"" + item + "\"";
    else if (object.contains(key))
      problem = key + " given twice";
    else if (key == "phase")
      problem = std::string("phase cannot be set") +
                (std::string(command) == "simulate" ? " (--phase chooses it)" : "");
    else if (!nlohmann::json::accept(value))  // every setting but phase is a number or a bool
      problem = item + ": \"" + value + "\" is not a number, true or false";
    if (!problem.empty()) {
      std::cerr << "error: " << command << ": --set: " << problem << "\n";
      return std::nullopt;
    }
    object[key] = nlohmann::json::parse(value);
  }
  return object;
}

}  // namespace

bool tissueStepCapOrReport(const ValveCase& valve_case, const SimulationSettings& settings,
                           const std::string& tissue_file) {
  if (stepCapProblem(valve_case, settings).empty()) return true;
  // The case's settings, overrides included, passed with the case's own tissue: the file that
  // replaced it is the cause (with uniform tissue the case may not pass: a fit's softer
  // tissue.json lengthens the step).
  Diagnostics diagnostics;
  diagnostics.error(tissue_file, "stiffness", tissueStepCapProblem(valve_case, settings, true));
  reportProblems(diagnostics);
  return false;
}

std::optional<SimulationSettings> caseSettingsOrReport(ValveCase& valve_case,
                                                       const std::string& case_dir, SettingsUse use,
                                                       const char* command,
                                                       const std::vector<std::string>& overrides,
                                                       const std::string& tissue_file) {
  // Named inside the case, under a "case DIR: N problem(s)" line, as loadCaseOrReport does.
  const std::string case_file = "case.json";
  Diagnostics diagnostics;
  const SimulationSettings own =
      settingsFromJson(valve_case.simulation_json, diagnostics, {}, case_file);
  // The library reads "phase" (a closure's direction), but a case's block has no say in it:
  // every command closes, and simulate --phase open opens after. Accepted, it was ignored.
  if (!valve_case.simulation_json.empty() &&
      nlohmann::json::parse(valve_case.simulation_json, nullptr, false).contains("phase"))
    diagnostics.error(case_file, "simulation.phase",
                      "a case's settings cannot choose the phase (simulate --phase open does)");
  SimulationSettings settings = own;
  const std::string overrides_source = std::string(command) + ": --set";
  if (!overrides.empty() && diagnostics.ok()) {
    const std::optional<nlohmann::json> object = settingOverridesOrReport(command, overrides);
    if (!object) return std::nullopt;
    settings = settingsFromJson(object->dump(), diagnostics, own, overrides_source);
    // Into the case as well, so that whatever reads its settings later (the metrics' contact
    // thickness, the figures) sees the run's.
    nlohmann::json simulation = valve_case.simulation_json.empty()
                                    ? nlohmann::json::object()
                                    : nlohmann::json::parse(valve_case.simulation_json);
    simulation.update(*object);
    valve_case.simulation_json = simulation.dump();
  }
  settings.phase = ClosurePhase::kClose;
  // metrics reads the settings (the leaflets' thickness) but runs no closure: the step cap is
  // not its business.
  if (diagnostics.ok() && use != SettingsUse::kMeasure) {
    if (const std::string problem = stepCapProblem(valve_case, settings); !problem.empty())
      reportStepCapProblem(problem, valve_case, own, settings, overrides_source,
                           use != SettingsUse::kCheck, tissue_file, diagnostics);
  }
  if (!diagnostics.ok()) {
    const auto of_case = std::count_if(diagnostics.problems().begin(), diagnostics.problems().end(),
                                       [&](const Problem& p) { return p.file == case_file; });
    if (of_case > 0) std::cerr << "case " << case_dir << ": " << of_case << " problem(s)\n";
    reportProblems(diagnostics);
    return std::nullopt;
  }
  // The default ramp was calibrated at 100 mmHg (10 mmHg per ms). Loaded much faster, a
  // prolapsing flap can overshoot into another equilibrium: the prolapse-P2 case with its true
  // cords at 200 mmHg closed with P2 under the anterior leaflet with the 10 ms ramp and with a
  // P2 flap with 20 or 40 ms (175 mmHg too; 150 mmHg the same with 10 and 40 ms).
  constexpr double kFastestCalibratedMmHgPerMs = 15.0;
  // ramp_ms 0 (the load at once) is the fastest of all.
  const double rate = settings.ramp_ms > 0.0 ? settings.pressure_mmhg / settings.ramp_ms
                                             : std::numeric_limits<double>::infinity();
  if (use == SettingsUse::kClose && settings.pressure_mmhg > 0.0 &&
      rate > kFastestCalibratedMmHgPerMs) {
    // %.3g: a 1e-300 ms ramp printed the rate with 300 digits.
    char how_fast[96] = "at once (ramp_ms 0) loads the valve";
    if (settings.ramp_ms > 0.0)
      std::snprintf(how_fast, sizeof how_fast, "over a %g ms ramp loads the valve at %.3g mmHg/ms",
                    settings.ramp_ms, rate);
    printNote(
        "%s: %g mmHg %s, faster than calibrated (10 mmHg/ms at the defaults): a "
        "prolapsing flap may land in another equilibrium; --set ramp_ms=%g keeps 10 "
        "mmHg/ms (docs/model.md)\n",
        command, settings.pressure_mmhg, how_fast, std::ceil(settings.pressure_mmhg / 10.0));
  }
  return settings;
}

bool optionsArePositive(const char* command,
                        std::initializer_list<std::pair<const char*, double>> options,
                        const char* what) {
  for (const auto& [option, value] : options) {
    if (!(value > 0.0) || !std::isfinite(value)) {
      std::cerr << "error: " << command << ": " << option << ": must be " << what << ", got "
                << value << "\n";
      return false;
    }
  }
  return true;
}

namespace {

// "<path> is a symbolic link to <target>, which does not exist" when `path` is a link whose
// target is missing, else "": creating the directory there, or a file through it, would
// fail only after the work (or replace the link instead of writing its target).
std::string danglingLinkProblem(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_symlink(fs::symlink_status(path, ec)) || fs::exists(path, ec)) return "";
  return path.string() + " is a symbolic link to " + fs::read_symlink(path, ec).string() +
         ", which does not exist";
}

// Why outputs cannot go to `directory` (created later if missing), or "" when they can: its
// nearest existing ancestor must be a directory in which a file can be created, and no
// missing part of the path may be a dangling symbolic link.
std::string outputPlaceProblem(const std::string& directory) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path requested = fs::absolute(directory.empty() ? fs::path(".") : fs::path(directory), ec);
  if (!requested.has_filename()) requested = requested.parent_path();  // "out/" is "out"
  fs::path existing = requested;
  while (!ec && !fs::exists(existing, ec) && existing.has_parent_path() &&
         existing != existing.parent_path()) {
    const std::string dangling = danglingLinkProblem(existing);
    if (!dangling.empty()) return dangling;
    existing = existing.parent_path();
  }
  if (ec) return ec.message();
  if (!fs::is_directory(existing, ec))  // the message names --out itself already
    return existing == requested ? "exists and is not a directory"
                                 : existing.string() + " is not a directory";
  // Creating a file is the only reliable test: access(W_OK) says yes to root everywhere,
  // /proc and read-only mounts included. mkstemp picks a name no other file has.
  std::string probe = (existing / ".chordfit-probe-XXXXXX").string();
  const int fd = ::mkstemp(probe.data());
  if (fd < 0)
    return "no file can be created in " + existing.string() + " (" + std::strerror(errno) + ")";
  ::close(fd);
  ::unlink(probe.c_str());
  return "";
}

bool reportOutputProblem(const char* command, const std::string& out, const std::string& problem) {
  if (problem.empty()) return true;
  std::cerr << "error: " << command << ": --out: " << out << ": " << problem << "\n";
  return false;
}

// An empty --out is a mistake (an unset variable in a script), not the current directory:
// make-valve used to write there and print "wrote /case.json", the others to fail after the
// work.
bool reportEmptyOutput(const char* command, const std::string& out) {
  if (!out.empty()) return false;
  std::cerr << "error: " << command << ": --out: must not be empty\n";
  return true;
}

// The paths a command writes are longer than --out: a staging directory (".staging-<pid>",
// within a nested command's too) and a file's temporary (".<name>.chordfit-tmp.<pid>"). An
// --out within the system's limits but not that much within failed after the work: at 4,060
// of PATH_MAX's 4,096 bytes (leaving the directories it had made), or with a file name of
// 250 bytes that its temporary took past NAME_MAX's 255. Lengths are bytes; pids up to 10
// digits.
constexpr std::size_t kTemporaryNameExtra = 1 + (sizeof(kTemporaryInfix) - 1) + 10;
constexpr std::size_t kStagingExtra = sizeof("/.staging-") - 1 + 10;

// `longer`: what the command writes that is longer than the path given.
std::string pathTooLong(const std::string& path, const std::string& longer) {
  return "a path of " + std::to_string(path.size()) + " bytes: " + longer +
         " would pass the system's limit of " + std::to_string(PATH_MAX - 1) +
         " bytes; give a shorter path";
}

// For an output directory whose longest file name is `longest_name`.
std::string directoryPathLengthProblem(const std::string& dir, const std::string& longest_name) {
  const std::size_t longest =
      dir.size() + 2 * kStagingExtra + 1 + longest_name.size() + kTemporaryNameExtra;
  return longest < PATH_MAX
             ? ""
             : pathTooLong(dir,
                           "the paths written under it (a staging directory and temporary names "
                           "included)");
}

// For an output file, written beside itself.
std::string filePathLengthProblem(const std::string& file) {
  if (file.size() + kTemporaryNameExtra >= PATH_MAX)
    return pathTooLong(file, "its temporary name while it is written");
  const std::size_t name = std::filesystem::path(file).filename().string().size();
  if (name + kTemporaryNameExtra <= NAME_MAX) return "";
  return "a file name of " + std::to_string(name) + " bytes: its temporary name while it is " +
         "written would pass the system's limit of " + std::to_string(NAME_MAX) +
         " bytes for a name; give a name of at most " +
         std::to_string(NAME_MAX - kTemporaryNameExtra) + " bytes";
}

}  // namespace

bool outputDirectoryUsable(const char* command, const std::string& directory,
                           const std::vector<std::string>& files,
                           const std::vector<std::string>& inputs) {
  if (reportEmptyOutput(command, directory)) return false;
  std::string longest_name;
  for (const std::string& name : files)
    if (name.size() > longest_name.size()) longest_name = name;
  if (!reportOutputProblem(command, directory, directoryPathLengthProblem(directory, longest_name)))
    return false;
  if (!reportOutputProblem(command, directory, outputPlaceProblem(directory))) return false;
  for (const std::string& name : files) {
    if (const auto problem = whatIsInTheWay(directory, name))
      return reportOutputProblem(command, problem->path.string(), problem->what);
    if (!outputSparesInputs(command, (std::filesystem::path(directory) / name).string(), inputs))
      return false;
  }
  return true;
}

bool outputSparesInputs(const char* command, const std::string& output,
                        const std::vector<std::string>& inputs) {
  for (const std::string& input : inputs) {
    std::error_code ec;
    if (!input.empty() && std::filesystem::equivalent(output, input, ec))
      return reportOutputProblem(command, output,
                                 std::string("is an input of this run; ") + command +
                                     " would write over it: give another --out, or copy the "
                                     "file elsewhere first");
  }
  return true;
}

std::vector<std::string> caseInputFiles(const std::string& case_dir, bool with_cords) {
  if (case_dir.empty()) return {};
  const std::filesystem::path dir(case_dir);
  std::vector<std::string> files = {(dir / "case.json").string()};
  std::string text;
  if (!readWholeFile(dir / "case.json", text)) return files;
  const nlohmann::json json = nlohmann::json::parse(text, nullptr, false);
  // Every string of the case file that names an existing file of the case: the mesh, the
  // annulus curves, tracings, tips, cords, tissue.
  // The case format nests file names two levels deep ({"annulus": {"closed": ...}}); the
  // depth limit keeps a deeply nested unknown key (refused later by the case's validation)
  // from exhausting the stack here.
  constexpr int kMaxDepth = 4;
  std::function<void(const nlohmann::json&, int)> collect = [&](const nlohmann::json& value,
                                                                int depth) {
    if (value.is_string()) {
      std::error_code ec;
      const std::filesystem::path file = dir / value.get<std::string>();
      if (!value.get<std::string>().empty() && std::filesystem::is_regular_file(file, ec))
        files.push_back(file.string());
    } else if (value.is_structured() && depth < kMaxDepth) {
      for (const auto& item : value) collect(item, depth + 1);
    }
  };
  if (json.is_discarded() || !json.is_object()) return files;
  for (const auto& [key, value] : json.items())
    if (with_cords || key != "cords") collect(value, 1);
  // The curve files a tracings file names ({"tracings": [{"file": ...}]}), relative to it.
  if (const auto t = json.find("tracings"); t != json.end() && t->is_string()) {
    const std::filesystem::path tracings_file = dir / t->get<std::string>();
    std::string tracings_text;
    if (readWholeFile(tracings_file, tracings_text)) {
      const nlohmann::json list = nlohmann::json::parse(tracings_text, nullptr, false);
      if (list.is_object() && list.contains("tracings") && list["tracings"].is_array()) {
        for (const nlohmann::json& entry : list["tracings"]) {
          if (!entry.is_object() || !entry.contains("file") || !entry["file"].is_string()) continue;
          const std::filesystem::path file =
              tracings_file.parent_path() / entry["file"].get<std::string>();
          std::error_code ec;
          if (std::filesystem::is_regular_file(file, ec)) files.push_back(file.string());
        }
      }
    }
  }
  return files;
}

bool outputFileUsable(const char* command, const std::string& file) {
  if (reportEmptyOutput(command, file)) return false;
  if (!reportOutputProblem(command, file, filePathLengthProblem(file))) return false;
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    return reportOutputProblem(command, file, "is a directory; give the file to write");
  if (std::filesystem::path(file).filename().empty())  // "new/": not there yet, or a file
    return reportOutputProblem(
        command, file,
        std::filesystem::exists(std::filesystem::path(file).parent_path(), ec)
            ? "ends in a separator, which names a directory, but a file is there; give the file "
              "to write"
            : "ends in a separator, which names a directory (none is there); give the file to "
              "write");
  if (!reportOutputProblem(command, file, danglingLinkProblem(file))) return false;
  if (!reportOutputProblem(command, file, specialFileProblem(file))) return false;
  return reportOutputProblem(
      command, file, outputPlaceProblem(std::filesystem::path(file).parent_path().string()));
}

std::vector<std::string> caseDirectoryFilesBesides(const std::vector<std::string>& declared) {
  std::vector<std::string> others;
  for (const std::string& name : syntheticCaseFileNames())
    if (std::find(declared.begin(), declared.end(), name) == declared.end()) others.push_back(name);
  return others;
}

int fitStepCapToMesh(ValveCase& valve_case) {
  const SimulationSettings defaults;
  const double dt = caseTimeStepMs(valve_case, defaults);
  if (!(dt > 0.0)) return 0;
  const double ramp_steps = std::ceil(defaults.ramp_ms / dt);
  if (!(5.0 * ramp_steps > defaults.max_steps)) return 0;
  // A mesh so fine (or not in millimetres) that no closure could run: validation refuses it;
  // no cap.
  const std::optional<int> cap = stepCapForRamp(ramp_steps);
  if (!cap) return 0;
  nlohmann::json simulation = nlohmann::json::parse(valve_case.simulation_json);
  simulation["max_steps"] = *cap;
  valve_case.simulation_json = simulation.dump();
  printNote(
      "simulation.max_steps = %d in case.json: at this mesh's time step (%.3g ms) "
      "the %g ms pressure ramp takes %.0f steps, too many to settle within the default cap of "
      "%d\n",
      *cap, dt, defaults.ramp_ms, ramp_steps, defaults.max_steps);
  return *cap;
}

int reportClosureFailure(const SimulationResult& result, const std::string& what,
                         const std::string& suffix) {
  std::cerr << "error: " << what << ": " << (result.diverged ? "simulation failed: " : "")
            << result.error << suffix << "\n";
  return result.diverged ? kExitSimulationFailed : kExitBadInput;
}

std::string closedValveSummary(const ValveMetrics& m, const std::string& indent) {
  std::string text;
  if (m.has_tracings) {
    text += indent +
            "prolapse (tracings):             " + joinSegments(m.tracing_prolapse.segments) + "\n";
    text += indent +
            "prolapse (mesh, tracing planes): " + joinSegments(m.section_prolapse.segments) +
            (m.prolapse_reconstructed ? "  -> reconstructed" : "  -> not reconstructed") + "\n";
  }
  text +=
      indent + "prolapse (mesh tissue):          " + joinSegments(m.mesh_prolapse.segments) + "\n";
  if (m.orifice.samples > 0) {
    char line[160];
    std::snprintf(
        line, sizeof line,
        "orifice covered (en face):       %.1f %% (open %.0f of %.0f mm²; leaflets ± %.2g mm)\n",
        100.0 * m.orifice.coverage(), m.orifice.open_area_mm2, m.orifice.orifice_area_mm2,
        m.orifice.tissue_radius_mm);
    text += indent + line;
  }
  text += indent + "leaflets passing through:        " +
          (m.self_intersections == 0
               ? std::string("none")
               : std::to_string(m.self_intersections) +
                     (m.self_intersections == 1 ? " intersecting triangle pair"
                                                : " intersecting triangle pairs") +
                     " (docs/performance.md, \"Self-intersections of coarse closures\")") +
          "\n";
  return text;
}

std::string duplicateTracingsNote(const ValveCase& valve_case) {
  constexpr int kNamedAtMost = 3;
  std::string note;
  int repeats = 0;
  const auto& tracings = valve_case.tracings;
  for (std::size_t t = 1; t < tracings.size(); ++t) {
    for (std::size_t u = 0; u < t; ++u) {
      if (tracings[t].points.rows() != tracings[u].points.rows() ||
          tracings[t].points != tracings[u].points)
        continue;
      if (++repeats <= kNamedAtMost)
        note += "note: tracings[" + std::to_string(t) + "] repeats tracings[" + std::to_string(u) +
                "] point for point: its points count again in the fit, and the fit's SDs "
                "(uncertainty.csv) come out narrower than the data warrant\n";
      break;
    }
  }
  if (repeats > kNamedAtMost)
    note += "note: " + counted(repeats - kNamedAtMost, "more tracing") +
            (repeats - kNamedAtMost == 1 ? " repeats an earlier one\n" : " repeat earlier ones\n");
  return note;
}

std::string caseSummary(const ValveCase& c) {
  std::ostringstream out;
  const ValveMesh& mesh = c.mesh;
  out << "case " << c.name << "\n";
  out << "  mesh:      " << mesh.V.rows() << " vertices, " << mesh.F.rows() << " triangles, area "
      << static_cast<long>(surfaceArea(mesh.V, mesh.F) + 0.5) << " mm²\n";
  out << "  leaflets:  " << mesh.leaflet_names.size();
  for (std::size_t l = 0; l < mesh.leaflet_names.size(); ++l) {
    out << (l == 0 ? " (" : ", ") << mesh.leaflet_names[l] << " "
        << (mesh.leaflet.array() == static_cast<int>(l)).count();
  }
  out << " vertices)\n";
  out << "  annulus:   ring of " << mesh.annulus.size() << " vertices, " << c.annulus_closed.rows()
      << " closed-state positions\n";
  Eigen::Index points = 0;
  for (const Tracing& t : c.tracings) points += t.points.rows();
  out << "  tracings:  " << counted(c.tracings.size(), "polyline") << ", "
      << counted(points, "point") << "\n";
  out << "  PM tips:   " << (c.tips ? std::to_string(c.tips->size()) : "none (heuristic)") << "\n";
  out << "  cords:     "
      << (c.cords ? counted(c.cords->cords.size(), "cord") + " on " +
                        counted(c.cords->tips.size(), "tip")
                  : "none (automatic placement + heuristic)")
      << "\n";
  return out.str();
}

}  // namespace chordfit::cli
