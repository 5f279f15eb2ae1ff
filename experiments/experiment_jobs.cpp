#include "experiments/experiment_jobs.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <vector>

#include <csignal>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/case_io.h"
#include "core/cordset_io.h"
#include "core/counted.h"
#include "core/mesh_io.h"
#include "core/synthetic_case.h"
#include "experiments/result_fields.h"

extern char** environ;

namespace chordfit::experiments {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

std::string formatNumber(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

// "LO,HI" for `fit --scale-bounds` (the bounds as %g prints them).
std::string scaleBoundsArgument(const ExperimentConfig& config) {
  return formatNumber(config.scale_bounds->first) + "," + formatNumber(config.scale_bounds->second);
}

// The command as a reader would type it from the source root: paths inside the source tree
// are shown relative to it (results record no machine-specific prefix).
std::string commandLine(const std::vector<std::string>& args) {
  const std::string root = std::string(CHORDFIT_SOURCE_DIR) + "/";
  std::string line;
  for (std::string a : args) {
    if (a.rfind(root, 0) == 0) a = a.substr(root.size());
    const bool plain = a.find_first_of(" '\"\\$") == std::string::npos;
    line += (line.empty() ? "" : " ") + (plain ? a : "'" + a + "'");
  }
  return line;
}

// The stop request and the running child, shared with the signal handler.
volatile std::sig_atomic_t g_stop_signal = 0;
volatile std::sig_atomic_t g_child_pid = 0;

// Ctrl-C reaches the running chordfit through the terminal's process group, but a `kill` of
// run_experiments alone would leave it running as an orphan: forward the signal. Only
// async-signal-safe calls here.
// SIGHUP sent to run_experiments stops the run as SIGTERM does, and the child gets SIGTERM
// (chordfit cleans up after SIGINT and SIGTERM). A closing terminal sends SIGHUP to the whole
// foreground group, chordfit included, which then dies without its cleanup; run shards under
// nohup or in a terminal that stays.
// The run itself reports and exits with the signal it received (SIGHUP: 129).
int signalForChild(int signal_number) { return signal_number == SIGHUP ? SIGTERM : signal_number; }

extern "C" void forwardStopSignal(int signal_number) {
  g_stop_signal = signal_number;
  const pid_t child = static_cast<pid_t>(g_child_pid);
  if (child > 0) ::kill(child, signalForChild(signal_number));
}

// A child that outlives a forwarded stop by this long (one that ignores or hangs on SIGINT /
// SIGTERM; chordfit ends within a step) is killed, so that a stop always ends the run.
constexpr std::chrono::seconds kStopGrace{5};

// waitpid's status of `pid`, or -1. Polls rather than blocks: the stop handlers restart a
// blocking waitpid (SA_RESTART), and a child deaf to the forwarded stop must still be ended.
int waitForChild(pid_t pid) {
  using Clock = std::chrono::steady_clock;
  std::optional<Clock::time_point> stop_seen;
  bool killed = false;
  for (;;) {
    int status = 0;
    const pid_t waited = waitpid(pid, &status, WNOHANG);
    if (waited == pid) return status;
    if (waited < 0 && errno != EINTR) return -1;
    if (g_stop_signal != 0 && !stop_seen) stop_seen = Clock::now();
    if (stop_seen && !killed && Clock::now() - *stop_seen > kStopGrace) {
      ::kill(pid, SIGKILL);
      killed = true;
      std::fprintf(stderr,
                   "run_experiments: the job's process %d did not end within %lld s of the stop "
                   "signal: killed (SIGKILL)\n",
                   static_cast<int>(pid), static_cast<long long>(kStopGrace.count()));
    }
    ::usleep(20000);  // 20 ms: a job's start and end are seen well within its own run time
  }
}

// Runs args[0] with stdout and stderr appended to `log`. Returns the exit code, or -1 when
// the program could not be started (e.g. missing executable), 128 + signal when killed; does
// not start it (128 + signal) when a stop was requested.
int runProgram(const std::vector<std::string>& args, const fs::path& log) {
  if (g_stop_signal != 0) return 128 + g_stop_signal;
  fs::create_directories(log.parent_path());
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  // The stop signals stay blocked from before the spawn until the child's pid is recorded, so
  // the handler never misses a child it should forward to; the child starts with them unblocked
  // and at their default action (even when run_experiments was started ignoring SIGINT).
  sigset_t stop_signals, previous;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  sigaddset(&stop_signals, SIGHUP);
  sigprocmask(SIG_BLOCK, &stop_signals, &previous);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setsigmask(&attributes, &previous);
  posix_spawnattr_setsigdefault(&attributes, &stop_signals);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, &attributes, argv.data(), environ);
  posix_spawnattr_destroy(&attributes);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned == 0) g_child_pid = pid;
  sigprocmask(SIG_SETMASK, &previous, nullptr);  // a pending stop is forwarded here
  if (spawned != 0) return -1;
  // A stop requested before the child existed.
  if (g_stop_signal != 0) ::kill(pid, signalForChild(g_stop_signal));
  const int status = waitForChild(pid);  // a wait status is never negative
  g_child_pid = 0;
  if (status < 0) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

// The stop signal run_experiments received, or else the one a child's exit code means (chordfit
// dies of SIGINT / SIGTERM, so 130 / 143; a SIGHUP forwarded as SIGTERM is still SIGHUP); 0 when
// the run goes on.
int stopSignalOf(int exit_code) {
  if (g_stop_signal != 0) return g_stop_signal;
  if (exit_code == 128 + SIGINT) return SIGINT;
  if (exit_code == 128 + SIGTERM) return SIGTERM;
  return 0;
}

std::string logTail(const fs::path& log, std::size_t lines = 6) {
  std::ifstream in(log);
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);) all.push_back(line);
  std::string tail;
  for (std::size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i) {
    tail += "\n    | " + all[i];
  }
  return tail;
}

StepOutcome failure(const std::string& what, int stop_signal = 0) {
  return {false, false, what, "", stop_signal};
}

// Runs a chordfit subcommand; on failure describes it with the log's last lines and sets
// `stop_signal` when the run is to stop (stopSignalOf).
bool runChordfit(const RunPaths& paths, std::vector<std::string> args, const fs::path& log,
                 std::string& error, int& stop_signal, std::string* command_out = nullptr) {
  args.insert(args.begin(), paths.chordfit.string());
  if (command_out) *command_out = commandLine(args);
  if (!fs::exists(paths.chordfit)) {
    error = "chordfit executable not found: " + paths.chordfit.string();
    return false;
  }
  const int code = runProgram(args, log);
  if (code == 0) return true;
  stop_signal = stopSignalOf(code);
  error = (code < 0 ? "could not start: " : "exit code " + std::to_string(code) + ": ") +
          commandLine(args) + " (log " + log.string() + ")" + logTail(log);
  return false;
}

json readJsonFile(const fs::path& path) {
  std::string text;
  if (!readWholeFile(path, text)) throw std::runtime_error(path.string() + ": file not found");
  try {
    return json::parse(text);
  } catch (const json::exception& e) {
    throw std::runtime_error(path.string() + ": not valid JSON: " + e.what());
  }
}

json requireKey(const json& j, const char* key, const fs::path& file) {
  if (!j.contains(key)) throw std::runtime_error(file.string() + ": missing key \"" + key + "\"");
  return j.at(key);
}

// The Table 1 metrics of a simulate or fit metrics.json, checked.
json tableMetrics(const json& m, const fs::path& file) {
  json t;
  for (const char* key : {"area_mm2", "min_mm", "median_mm", "max_mm", "mean_mm", "sd_mm",
                          "prolapse_reconstructed", "prolapse_segments"}) {
    t[key] = requireKey(m, key, file);
  }
  t["tracing_prolapse_segments"] = m.value("tracing_prolapse_segments", json(nullptr));
  // The mesh's prolapse in the tracing planes and the tissue judgement (core/metrics.h).
  for (const char* key : {"section_prolapse_segments", "tissue_prolapse_reconstructed"}) {
    t[key] = m.value(key, json(nullptr));
  }
  return t;
}

// The true cord set on the CASE mesh (core/synthetic_case.h, trueCordsOnCaseMesh) from the
// case's cords.json and truth/cords.json.
CordSet trueCordsOnCaseMesh(const fs::path& case_dir) {
  Diagnostics diagnostics;
  CordSet case_cords, truth_cords;
  if (!readCordSet(case_dir / "cords.json", "cords.json", case_cords, diagnostics) ||
      !readCordSet(case_dir / "truth" / "cords.json", "truth/cords.json", truth_cords,
                   diagnostics)) {
    std::ostringstream out;
    diagnostics.print(out);
    throw std::runtime_error(case_dir.string() + ": " + out.str());
  }
  try {
    return chordfit::trueCordsOnCaseMesh(case_cords, truth_cords);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(case_dir.string() + ": cords.json, truth/cords.json: " + e.what());
  }
}

// Distance (mm) of each cord's attachment, in the TRUE closed state, from the nearest
// tracing plane: how directly the tracings observe the leaflet that cord holds.
std::vector<double> attachmentPlaneDistances(const fs::path& case_dir, const json& truth) {
  Diagnostics diagnostics;
  const auto valve_case = loadCase(case_dir, diagnostics);
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  if (!valve_case ||
      !readMesh(case_dir / "truth" / "closed.ply", V, F, diagnostics, "truth/closed.ply")) {
    std::ostringstream out;
    diagnostics.print(out);
    throw std::runtime_error(case_dir.string() + ": " + out.str());
  }
  std::vector<double> distances;
  for (const json& cord : truth.at("cords")) {
    // The cord's insertion on the true closed mesh: its point when the cohort has one.
    Eigen::Vector3d p = V.row(cord.at("truth_vertex").get<int>()).transpose();
    if (cord.contains("truth_point") && cord.at("truth_point").is_object()) {
      const json& point = cord.at("truth_point");
      p.setZero();
      for (int m = 0; m < 3; ++m) {
        p += point.at("weights").at(m).get<double>() *
             V.row(point.at("vertices").at(m).get<int>()).transpose();
      }
    }
    double nearest = std::numeric_limits<double>::infinity();
    for (const Tracing& t : valve_case->tracings) {
      nearest = std::min(nearest, std::abs(t.plane_normal.dot(p - t.plane_origin)));
    }
    distances.push_back(nearest);
  }
  return distances;
}

// Per-cord rest length against the truth; ruptured cords are marked (their true length is
// a placeholder for "never taut", nothing a fitter can or should recover).
json cordRecovery(const fs::path& case_dir, const fs::path& cords_file) {
  const json truth = readJsonFile(case_dir / "truth" / "truth.json");
  Diagnostics diagnostics;
  CordSet fitted;
  if (!readCordSet(cords_file, cords_file.string(), fitted, diagnostics)) {
    std::ostringstream out;
    diagnostics.print(out);
    throw std::runtime_error(out.str());
  }
  const json& cords = truth.at("cords");
  if (fitted.cords.size() != cords.size()) {
    throw std::runtime_error(cords_file.string() + ": " + std::to_string(fitted.cords.size()) +
                             " cords, the truth has " + std::to_string(cords.size()));
  }
  const std::vector<double> distances = attachmentPlaneDistances(case_dir, truth);
  json rows = json::array();
  for (std::size_t i = 0; i < cords.size(); ++i) {
    const double true_length = cords[i].at("true_rest_length_mm").get<double>();
    const double length = fitted.cords[i].rest_length;
    json row = {{"index", i},
                {"segment", cords[i].at("segment")},
                {"kind", cords[i].at("kind")},
                {"ruptured", cords[i].at("ruptured")},
                {"plane_distance_mm", distances[i]},
                {"rest_length_mm", length},
                {"true_rest_length_mm", true_length},
                {"relative_error", length / true_length - 1.0}};
    // Cases made before truth.json recorded the tension have no such key.
    if (cords[i].contains("true_closed_tension_n"))
      row["taut_in_truth"] = cords[i].at("true_closed_tension_n").get<double>() > 0.0;
    rows.push_back(row);
  }
  return rows;
}

// AvgD against forward simulations from a fit's convergence.csv. The column names are read
// from the header: the simulation count is the column named forward_sims (or sims), the
// deviation the one named mean_mm (or mean_deviation_mm).
json convergenceTrace(const fs::path& csv_file) {
  std::ifstream in(csv_file);
  if (!in) throw std::runtime_error(csv_file.string() + ": file not found");
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  std::istringstream hs(line);
  for (std::string cell; std::getline(hs, cell, ',');) header.push_back(cell);
  auto column = [&](std::initializer_list<const char*> names) {
    for (const char* name : names) {
      for (std::size_t k = 0; k < header.size(); ++k) {
        if (header[k] == name) return static_cast<int>(k);
      }
    }
    return -1;
  };
  const int sims = column({"forward_sims", "sims", "forward_simulations"});
  const int mean = column({"mean_mm", "mean_deviation_mm", "avgd_mm"});
  if (sims < 0 || mean < 0) {
    throw std::runtime_error(csv_file.string() + ": header \"" + line +
                             "\" has no forward_sims / mean_mm column");
  }
  json x = json::array(), y = json::array();
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::istringstream ls(line);
    for (std::string cell; std::getline(ls, cell, ',');) cells.push_back(cell);
    if (static_cast<int>(cells.size()) <= std::max(sims, mean)) continue;
    x.push_back(std::stod(cells[sims]));
    y.push_back(std::stod(cells[mean]));
  }
  return {{"forward_sims", x}, {"mean_mm", y}};
}

// A directory under `source` holding a case generated with exactly `spec`'s options.
fs::path matchingSourceCase(const CaseSpec& spec, const fs::path& source) {
  if (source.empty() || !fs::is_directory(source)) return {};
  std::vector<fs::path> candidates;
  for (const auto& entry : fs::directory_iterator(source)) candidates.push_back(entry.path());
  std::sort(candidates.begin(), candidates.end());
  for (const fs::path& dir : candidates) {
    if (fs::exists(dir / "case.json") && !caseOptionMismatch(spec, dir)) return dir;
  }
  return {};
}

}  // namespace

std::optional<OptionMismatch> resultOptionMismatch(const json& result, const JobSpec& job,
                                                   const CaseSpec& spec,
                                                   const ExperimentConfig& config) {
  auto differs = [&](const char* key, double wanted) {
    return result.contains(key) &&
           !(result.at(key).is_number() && std::abs(result.at(key).get<double>() - wanted) < 1e-12);
  };
  auto shown = [&](const char* key) {
    const json& v = result.at(key);
    return v.is_number() ? formatNumber(v.get<double>()) : v.dump();
  };
  const struct {
    const char* key;
    const char* option;
    double wanted;
  } case_options[] = {{"edge_mm", "--edge", spec.edge_mm},
                      {"planes", "--plan", static_cast<double>(spec.planes)},
                      {"noise_mm", "--plan", spec.noise_mm},
                      {"dropout", "--plan", spec.dropout}};
  for (const auto& o : case_options) {
    if (differs(o.key, o.wanted))
      return OptionMismatch{o.key, o.option, shown(o.key), formatNumber(o.wanted)};
  }
  if (job.method != Method::kFit) return std::nullopt;
  if (differs("max_sims", config.max_sims)) {
    return OptionMismatch{"max_sims", "--max-sims", shown("max_sims"),
                          std::to_string(config.max_sims)};
  }
  // The fit's default bounds are not written down here: no scale_bounds in the result is the
  // default, and only the default matches it (an explicit 0.7,1.5 is refused, to be safe).
  const std::string default_bounds = "the fit's default";
  std::string recorded = default_bounds;
  if (result.contains("scale_bounds")) {
    const json& b = result.at("scale_bounds");
    recorded = b.is_array() && b.size() == 2 && b[0].is_number() && b[1].is_number()
                   ? formatNumber(b[0].get<double>()) + "," + formatNumber(b[1].get<double>())
                   : b.dump();
  }
  const std::string requested = config.scale_bounds ? scaleBoundsArgument(config) : default_bounds;
  if (recorded != requested)
    return OptionMismatch{"scale_bounds", "--scale-bounds", recorded, requested};
  return std::nullopt;
}

std::string otherPlanHint(const OptionMismatch& m, const std::string& plan) {
  // The plan default a recorded field takes, as the mismatch shows it.
  auto planValue = [&](const ExperimentConfig& c) -> std::optional<std::string> {
    if (m.field == "edge_mm" || m.field == "generation.case_edge_mm")
      return formatNumber(c.edge_mm);
    if (m.field == "generation.truth_edge_mm") return formatNumber(c.edge_mm / 2);
    if (m.field == "planes" || m.field == "generation.planes") return formatNumber(c.planes);
    if (m.field == "max_sims") return formatNumber(c.max_sims);
    return std::nullopt;
  };
  const std::pair<const char*, ExperimentConfig> plans[] = {
      {"full", fullConfig()}, {"reduced", reducedConfig()}, {"smoke", smokeConfig()}};
  for (const auto& [name, config] : plans) {
    if (name == plan) continue;
    const auto value = planValue(config);
    if (!value || *value != m.recorded) continue;
    for (const auto& [own_name, own_config] : plans) {
      if (own_name == plan && planValue(own_config) == value) return "";
    }
    return std::string(" (--plan ") + name + "'s value: were they made with --plan " + name + "?)";
  }
  return "";
}

std::optional<OptionMismatch> caseOptionMismatch(const CaseSpec& spec, const fs::path& case_dir) {
  std::string text;
  if (!readWholeFile(case_dir / "truth" / "truth.json", text)) {
    return OptionMismatch{"truth/truth.json", "--work", "missing", "a case made by make-case"};
  }
  const json truth = json::parse(text, nullptr, false);
  if (truth.is_discarded() || !truth.is_object()) {
    return OptionMismatch{"truth/truth.json", "--work", "not JSON", "a case made by make-case"};
  }
  const json generation = truth.value("generation", json::object());
  if (truth.value("preset", "") != spec.preset) {
    return OptionMismatch{"preset", "--presets", truth.value("preset", json()).dump(), spec.preset};
  }
  if (truth.value("seed", json()) != json(spec.seed)) {
    return OptionMismatch{"seed", "--seeds", truth.value("seed", json()).dump(),
                          std::to_string(spec.seed)};
  }
  const struct {
    const char* key;
    const char* option;
    double wanted;
  } options[] = {{"case_edge_mm", "--edge", spec.edge_mm},
                 {"truth_edge_mm", "--edge", spec.edge_mm / 2},
                 {"planes", "--plan", static_cast<double>(spec.planes)},
                 {"noise_mm", "--plan", spec.noise_mm},
                 {"dropout_fraction", "--plan", spec.dropout}};
  for (const auto& o : options) {
    const json value = generation.value(o.key, json());
    if (value.is_number() && std::abs(value.get<double>() - o.wanted) < 1e-12) continue;
    return OptionMismatch{
        std::string("generation.") + o.key, o.option,
        value.is_number() ? formatNumber(value.get<double>()) : std::string("not recorded"),
        formatNumber(o.wanted)};
  }
  return std::nullopt;
}

void installStopHandlers() {
  struct sigaction action = {};
  action.sa_handler = forwardStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGHUP, &action, nullptr);
}

void restoreDefaultStopHandlers() {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  std::signal(SIGHUP, SIG_DFL);
}

int stopSignal() { return g_stop_signal; }

fs::path caseDirectory(const RunPaths& paths, const std::string& case_id) {
  return paths.work / "cases" / case_id;
}

fs::path jobResultPath(const RunPaths& paths, const std::string& job_id) {
  return paths.results / "jobs" / (job_id + ".json");
}

StepOutcome ensureCase(const CaseSpec& spec, const RunPaths& paths) {
  const fs::path dir = caseDirectory(paths, spec.id);
  if (fs::exists(dir / "case.json")) return {true, true, "", "present"};
  const fs::path staging =
      paths.work / "cases" / (".staging-" + spec.id + "-" + std::to_string(::getpid()));
  fs::remove_all(staging);
  const fs::path log = paths.work / "logs" / ("case_" + spec.id + ".txt");
  std::string error;
  int stop_signal = 0;
  const auto start = Clock::now();
  std::string how = "generated";
  if (const fs::path source = matchingSourceCase(spec, paths.case_source); !source.empty()) {
    // A copy that fails (an unreadable file) fails this case alone and leaves no staging.
    std::error_code copy_error;
    fs::create_directories(staging, copy_error);
    if (!copy_error) fs::copy(source, staging, fs::copy_options::recursive, copy_error);
    if (copy_error) {
      std::error_code ignored;
      fs::remove_all(staging, ignored);
      return failure("case " + spec.id + ": cannot copy " + source.string() +
                     " (--case-source): " + copy_error.message());
    }
    how = "copied from " + source.string();
  } else if (!runChordfit(
                 paths,
                 {"make-case", "--preset", spec.preset, "--seed", std::to_string(spec.seed),
                  "--edge", formatNumber(spec.edge_mm), "--planes", std::to_string(spec.planes),
                  "--noise", formatNumber(spec.noise_mm), "--dropout", formatNumber(spec.dropout),
                  "--threads", "1", "--out", staging.string(), "--quiet"},
                 log, error, stop_signal)) {
    fs::remove_all(staging);
    return failure("case " + spec.id + ": " + error, stop_signal);
  }
  std::error_code ec;
  fs::rename(staging, dir, ec);  // fails when another shard was first: same files, keep theirs
  if (ec) fs::remove_all(staging);
  if (!fs::exists(dir / "case.json")) {
    // The rename fails onto a directory that is there already without a case (left by an
    // older or interrupted run, or made by hand).
    return failure("case " + spec.id + ": " + dir.string() +
                   (fs::exists(dir) ? " is there without a case.json (left half-made?): remove it"
                                    : " missing after generation"));
  }
  char seconds[32];
  std::snprintf(seconds, sizeof seconds, " in %.1f s",
                std::chrono::duration<double>(Clock::now() - start).count());
  return {true, false, "", how + seconds};
}

namespace {

// The job itself (runJob decides whether it runs and what becomes of an old result).
StepOutcome runJobSteps(const ExperimentPlan& plan, const ExperimentConfig& config,
                        const JobSpec& job, const RunPaths& paths, const fs::path& result_path,
                        const std::string& unusable) {
  const CaseSpec& spec = findCase(plan, job.case_id);
  const StepOutcome made = ensureCase(spec, paths);
  if (!made.ok) return made;

  const fs::path case_dir = caseDirectory(paths, spec.id);
  const fs::path run_dir = paths.work / "runs" / job.id;
  const fs::path log = run_dir / "log.txt";
  fs::remove_all(run_dir);
  fs::create_directories(run_dir);
  std::string error, command;
  int stop_signal = 0;
  json result = {{"job", job.id},           {"case", spec.id},         {"preset", spec.preset},
                 {"seed", spec.seed},       {"planes", spec.planes},   {"noise_mm", spec.noise_mm},
                 {"dropout", spec.dropout}, {"edge_mm", spec.edge_mm}, {"method", methodTag(job)},
                 {"label", job.label}};
  const auto start = Clock::now();
  try {
    fs::path cords_file;
    if (job.method == Method::kFit) {
      const std::string max_sims = std::to_string(config.max_sims);
      std::vector<std::string> fit_args = {"fit",         case_dir.string(),
                                           "--params",    job.params,
                                           "--optimizer", job.optimizer,
                                           "--max-sims",  max_sims,
                                           "--threads",   std::to_string(config.fit_threads)};
      if (config.fd_warm) fit_args.push_back("--fd-warm");
      if (job.tissue_prefit) fit_args.push_back("--tissue-prefit");
      // The groups fit is the paper's manual workflow (group factors on uniform tissue), the
      // benchmark's manual-like baseline: no softer tissue.
      if (job.params == "groups") fit_args.push_back("--no-tissue-retry");
      if (config.scale_bounds) {
        fit_args.insert(fit_args.end(), {"--scale-bounds", scaleBoundsArgument(config)});
      }
      fit_args.insert(fit_args.end(), {"--out", run_dir.string()});
      if (!runChordfit(paths, fit_args, log, error, stop_signal, &command)) {
        return failure("job " + job.id + ": " + error, stop_signal);
      }
      cords_file = run_dir / "cords.json";
      result["params"] = job.params;
      result["optimizer"] = job.optimizer;
      result["max_sims"] = config.max_sims;
      result["fd_warm"] = config.fd_warm;
      result["tissue_prefit"] = job.tissue_prefit;
      if (config.scale_bounds) {
        result["scale_bounds"] = {config.scale_bounds->first, config.scale_bounds->second};
      }
    } else {
      cords_file = case_dir / "cords.json";
      if (job.method == Method::kTruth) {
        cords_file = run_dir / "true_cords_on_case_mesh.json";
        writeCordSet(cords_file, trueCordsOnCaseMesh(case_dir));
        const fs::path floor_file = case_dir / "truth" / "metrics.json";
        result["noise_floor"] = tableMetrics(readJsonFile(floor_file), floor_file);
      }
      if (!runChordfit(paths,
                       {"simulate", case_dir.string(), "--cords", cords_file.string(), "--quiet",
                        "--threads", "1", "--out", run_dir.string()},
                       log, error, stop_signal, &command)) {
        return failure("job " + job.id + ": " + error, stop_signal);
      }
    }
    const double wall = std::chrono::duration<double>(Clock::now() - start).count();
    const fs::path metrics_file = run_dir / "metrics.json";
    const json metrics = readJsonFile(metrics_file);
    result["metrics"] = tableMetrics(metrics, metrics_file);
    if (job.method == Method::kFit) {
      for (const char* key : {"forward_sims", "fit_seconds", "initial_mean_mm"}) {
        result[key] = requireKey(metrics, key, metrics_file);
      }
      // Closures that reached the step cap (their state the mean of the last steps); recorded
      // since 2026-11-27, so the committed count can be summed from the job files.
      result["unsettled_sims"] = requireKey(metrics, "unsettled_sims", metrics_file);
      // Whether the fit ran again on softer tissue (fit's tissue retry, docs/fitting.md); absent
      // from results before it.
      if (metrics.contains("tissue_retry")) {
        const json& retry = metrics.at("tissue_retry");
        result["tissue_retry"] = {{"ran", retry.value("ran", false)},
                                  {"kept", retry.value("kept", false)},
                                  {"tissue", retry.value("tissue", json::array())}};
      }
      // --tissue-prefit asked (`tissue_prefit`) and whether it ran: a small budget skips it,
      // and its Table 1 row is then the per-cord fit's (the smoke run's 80 closures).
      if (job.tissue_prefit)
        result["tissue_prefit_ran"] = requireKey(metrics, "tissue_prefit_ran", metrics_file);
      result["convergence"] = convergenceTrace(run_dir / "convergence.csv");
    } else {
      result["forward_sims"] = 1;
      result["converged"] = requireKey(metrics, "converged", metrics_file);
      result["steps"] = requireKey(metrics, "steps", metrics_file);
    }
    result["wall_seconds"] = wall;
    result["command"] = command;
    result["revision"] = paths.revision;
    if (!paths.machine.empty()) result["machine"] = paths.machine;
    result["cords"] = cordRecovery(case_dir, cords_file);
  } catch (const std::exception& e) {
    return failure("job " + job.id + ": " + e.what());
  }
  writeFileAtomically(result_path, result.dump(1) + "\n");
  char numbers[96];
  const int sims = result["forward_sims"].get<int>();
  std::snprintf(numbers, sizeof numbers, "AvgD %.2f mm, %d %s, %.1f s",
                result["metrics"]["mean_mm"].is_number()
                    ? result["metrics"]["mean_mm"].get<double>()
                    : std::nan(""),
                sims, nounFor(sims, "sim").c_str(), result["wall_seconds"].get<double>());
  return {true, false, "",
          (unusable.empty() ? "" : "the result there " + unusable + ", so ran again: ") + numbers};
}

}  // namespace

StepOutcome runJob(const ExperimentPlan& plan, const ExperimentConfig& config, const JobSpec& job,
                   const RunPaths& paths, bool force) {
  const fs::path result_path = jobResultPath(paths, job.id);
  std::string unusable;
  if (!force && fs::exists(result_path)) {
    unusable = jobResultProblem(result_path, job.id);
    if (unusable.empty()) return {true, true, "", "result present"};
  }
  const StepOutcome outcome = runJobSteps(plan, config, job, paths, result_path, unusable);
  // A rerun that failed leaves no result (merge and check then report the job missing): a
  // failed --force rerun left the old one, which merge tabulated without a word. A stopped
  // one (Ctrl-C) keeps it: the stop is not the job's failure.
  if (!outcome.ok && outcome.stop_signal == 0) {
    std::error_code removed;
    fs::remove(result_path, removed);
  }
  return outcome;
}

}  // namespace chordfit::experiments
