// chordfit fit: fit the cord rest lengths (and optionally the PM tips) of a case to its
// tracings (issue 5). runFit reads as its stages: the options and inputs checked
// (fit_inputs.h), inverse::fitCords with its progress lines, the outputs written
// (fit_outputs.h: the closed mesh and its metrics by the simulate command's code path, then
// metrics.json extended with the fit's keys) and the summary on the terminal.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "core/counted.h"
#include "inverse/fit_cords.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/fit_inputs.h"
#include "tools/fit_outputs.h"
#include "tools/fit_report.h"
#include "tools/shell_word.h"

namespace chordfit::cli {

namespace {

using inverse::IterationRecord;

// Options given to a fit they do not act on: a note each (the run goes on; the user may have
// meant --params scales+tips, or Ceres). After the values are checked, so that a refused
// value is not first noted as unused. On stdout, as the fit's other notes.
void noteOptionsThatDoNotAct(const FitCommandOptions& o) {
  if (o.params != "scales+tips") {
    for (const char* option : {"--tip-box", "--tip-weight", "--fd-tip-step"})
      if (optionGiven(o.given_options, option))
        printNote("fit: %s acts only with --params scales+tips (this fit: --params %s)\n", option,
                  o.params.c_str());
  }
  // The finite differences serve Ceres' Jacobians; NLopt's methods take none, so with them
  // these options reach only the uncertainty's Jacobian, and nothing without it.
  if (o.optimizer != "ceres") {
    for (const char* option : {"--fd-step", "--fd-tip-step", "--fd-warm", "--fd-slack-closures"})
      if (optionGiven(o.given_options, option))
        printNote(
            "fit: %s acts only on %s with --optimizer %s (NLopt's methods take no "
            "derivatives)\n",
            option,
            o.uncertainty
                ? "the steps after the fit (the uncertainty's Jacobian, the locked-cord probe)"
                : "Ceres' Jacobians, so on nothing here (--no-uncertainty)",
            o.optimizer.c_str());
  }
}

// --- Stages 3 and 4: the fit's options and its progress lines ---

// Stage 3. The options of inverse::fitCords as the command's options ask for them, without
// progress callbacks (reportProgressOnStdout adds them).
inverse::FitOptions fitOptionsFor(const FitCommandOptions& o, inverse::ParameterMode mode) {
  inverse::FitOptions options;
  options.mode = mode;
  options.bounds.scale_lower = o.scale_bounds[0];
  options.bounds.scale_upper = o.scale_bounds[1];
  options.bounds.tip_box_mm = o.tip_box_mm;
  options.prefit.enabled = o.prefit;
  options.segment_prefit.enabled = o.prefit;
  options.tissue_prefit.enabled = o.tissue_prefit;
  options.tissue_retry = o.tissue_retry;
  options.slack_release.enabled = o.slack_release;
  options.optimizer = o.optimizer;
  options.max_sims = o.max_sims;
  options.finite_difference.threads = o.threads;
  options.finite_difference.scale_step = o.fd_scale_step;
  options.finite_difference.tip_step_mm = o.fd_tip_step_mm;
  options.finite_difference.warm_start = o.fd_warm_start;
  options.finite_difference.skip_slack = !o.fd_slack_closures;
  options.residual.own_leaflet = o.distance == "own-leaflet";
  options.residual.section_weight = o.section_weight;
  options.residual.weights.tip_per_mm = o.tip_weight;
  options.uncertainty = o.uncertainty;
  options.probe_locked = o.uncertainty;  // the after-fit diagnostics go together
  return options;
}

// One line of an optimisation's progress on stdout.
void printIterationLine(const IterationRecord& r) {
  // Columns aligned within each optimisation: the stage names of one ("segments" the
  // longest) and of the tissue retry's ("retry release" the longest).
  const int stage_width = r.stage.rfind("retry ", 0) == 0 ? 13 : 8;
  std::printf("%-*s iter %4d  cost %10.4f  best %10.4f  mean %7.4f mm  sims %4d  %7.1f s\n",
              stage_width, r.stage.c_str(), r.iteration, r.cost, r.best_cost, r.mean_deviation_mm,
              r.forward_sims, r.elapsed_s);
  std::fflush(stdout);
}

// Stage 4 (not with --quiet). Prints what is about to be fitted, and sets `options`' callbacks
// to print each stage and iteration on stdout as the fit goes.
void reportProgressOnStdout(const FitCommandOptions& o, const FitInputs& inputs,
                            inverse::FitOptions& options) {
  std::printf("fitting %s: %s, %s, %s, at most %s, %s\n", inputs.valve_case.name.c_str(),
              counted(inputs.seed.cords.size(), "cord").c_str(), o.params.c_str(),
              o.optimizer.c_str(), counted(o.max_sims, "forward run").c_str(),
              counted(o.threads, "thread").c_str());
  const std::string skip_reason = inverse::prefitSkipReason(inputs.seed);
  if (o.prefit && !skip_reason.empty()) std::printf("pre-fits skipped: %s\n", skip_reason.c_str());
  options.on_stage = [](const std::string& line) {
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  };
  options.on_iteration = printIterationLine;
}

// Stage 5, inverse::fitCords, failed: reports why the fit did not run to its end and returns the
// exit code.
int reportFitFailure(const FitCommandOptions& o, const inverse::FitOutcome& fit) {
  std::cerr << "error: " << o.case_dir << ": " << fit.error << "\n";
  return fit.error_is_input ? kExitBadInput : kExitSimulationFailed;
}

// --- Stage 7: the summary on the terminal ---

// "fit: ceres after N forward runs, T s (termination)", or the pre-fits' line when the
// optimiser took no step.
void printFitEndLine(const FitCommandOptions& o, const inverse::FitOutcome& fit) {
  const std::string no_step = optimiserNoStep(fit, o.optimizer);
  if (no_step.empty())
    std::printf("fit: %s after %s, %.1f s (%s)\n", o.optimizer.c_str(),
                counted(fit.forward_sims, "forward run").c_str(), fit.seconds,
                fit.termination.c_str());
  else  // "ceres after 57 forward runs" credited it with the pre-fits' work
    std::printf("fit: %s (%s), %.1f s (%s)\n", counted(fit.forward_sims, "forward run").c_str(),
                no_step.c_str(), fit.seconds, fit.termination.c_str());
}

// A note when a derivative-free local NLopt method stopped on its tolerance with much of the
// budget left.
void noteEarlyDerivativeFreeStop(const FitCommandOptions& o, const inverse::FitOutcome& fit) {
  // NLopt's local methods stop on a relative cost change between evaluations, which a
  // simulator's map can meet far from a minimum (bobyqa on the quick start's case: AvgD
  // 0.73 mm after 137 of 400 closures, where ceres reaches 0.40; after 137 of 150 too, two
  // evaluations of the same cost, so the note does not wait for half the budget).
  const auto driver = inverse::makeOptimizer(o.optimizer);
  const int unused = o.max_sims - fit.forward_sims;
  if (driver && driver->localDerivativeFree() && fit.termination.rfind("converged", 0) == 0 &&
      unused >= std::max(5, o.max_sims / 20)) {
    printNote(
        "%s stopped on its tolerance with %d of --max-sims %d %s unused; a "
        "derivative-free local method can stop early on a simulator's map (compare with "
        "--optimizer ceres, the default)\n",
        o.optimizer.c_str(), unused, o.max_sims, nounFor(o.max_sims, "closure").c_str());
  }
}

// The uncertainty's summary line, or a note on why it could not be computed.
void printUncertaintySummary(const FitCommandOptions& o, const inverse::FitOutcome& fit) {
  if (fit.uncertainty.ok()) {
    std::printf(
        "uncertainty: %d of %d free cords determined to better than 3 %% (residual SD %.2f mm, "
        "correlated over %.1f points; %s, %.1f s; report.md, uncertainty.csv)\n",
        identifiedCords(fit), freeCords(fit), fit.uncertainty.sigma_mm,
        fit.uncertainty.correlation_time,
        extraClosures(fit.uncertainty.jacobian_sims, fit.uncertainty.unsettled_sims).c_str(),
        fit.uncertainty_seconds);
  } else if (o.uncertainty && !fit.uncertainty.error.empty()) {
    printNote("%s\n", fit.uncertainty.error.c_str());
  }
}

// When the fitted closure is on softer tissue, the simulate command that reproduces it.
void printSofterTissueReproduction(const FitCommandOptions& o, const inverse::FitOutcome& fit) {
  if (fit.tissue.size() == 0) return;
  // compare and simulate close cords on the case's own tissue unless told otherwise.
  const std::filesystem::path out_dir(o.out_dir);
  std::cout << "the fitted closure is on softer tissue ("
            << (fit.tissue_retry.kept ? "tissue retry" : "tissue pre-fit")
            << "): chordfit simulate " << shellWord(o.case_dir) << " --cords "
            << shellWord((out_dir / "cords.json").string()) << " --tissue "
            << shellWord((out_dir / "tissue.json").string())
            << " reproduces it (compare: --tissues)\n";
}

// Stage 7. The fit's summary: how it ended, notes on the run, the seed and fitted closures
// side by side (Table 1), advice, and the files written (stdout; notes on stderr).
void printFitSummary(const FitCommandOptions& o, const ValveCase& valve_case,
                     const inverse::FitOutcome& fit, const WrittenFit& written) {
  printFitEndLine(o, fit);
  noteEarlyDerivativeFreeStop(o, fit);
  if (fit.unsettled_sims > 0) {
    printNote(
        "%d of the %d forward runs reached the step cap without settling (their state is "
        "the mean over the last steps; docs/performance.md)\n",
        fit.unsettled_sims, fit.forward_sims);
  }
  printUncertaintySummary(o, fit);
  if (const std::string why = tissuePrefitNotRun(fit, o); !why.empty())
    printNote("--tissue-prefit %s (the cords were fitted on the case's tissue)\n",
              why.c_str());  // report.md said so; the terminal did not
  std::cout << tipOffsetsLine(fit);
  if (fit.tissue_retry.ran || !fit.tissue_retry.skipped.empty())
    std::cout << "tissue retry: " << tissueRetryLine(fit, o) << "\n";
  printLockedProbeSummary(valve_case, o, fit);
  std::cout << table1Header("Cord set") << table1Row("seed", written.seed_metrics)
            << table1Row("fit", written.fit_metrics);
  if (const std::string note = worseThanSeedNote(fit); !note.empty()) printNote("%s", note.c_str());
  if (const std::string hint = missedProlapseHint(valve_case, o, fit, written.fit_metrics);
      !hint.empty())
    printNote("%s", hint.c_str());
  printSofterTissueReproduction(o, fit);
  std::cout << wroteLine(o.out_dir, written.published) << "\n";
}

}  // namespace

// The fit as a sequence of stages, each of which reports its own failure.
// The stages, numbered as their functions' comments number them: 1-2 options and inputs
// (fit_inputs.h), 3-4 the fit's options and progress lines, 5 the fit, 6 the files
// (fit_outputs.h), 7 the summary.
int runFit(const FitCommandOptions& o) {
  const auto mode = checkOptionValues(o);
  if (!mode) return kExitBadInput;
  const auto inputs = loadFitInputs(o, *mode);
  if (!inputs) return kExitBadInput;
  noteOptionsThatDoNotAct(o);  // every input checked

  inverse::FitOptions options = fitOptionsFor(o, *mode);
  if (!o.quiet) reportProgressOnStdout(o, *inputs, options);
  const inverse::FitOutcome fit =
      inverse::fitCords(inputs->valve_case, inputs->seed, inputs->settings, options);
  if (!fit.ok()) return reportFitFailure(o, fit);

  const WrittenFit written = writeFitOutputs(o, inputs->valve_case, fit);
  if (written.exit_code != kExitOk) return written.exit_code;
  printFitSummary(o, inputs->valve_case, fit, written);
  return kExitOk;
}

std::vector<std::string> fitOutputFiles() {
  // tissue.json only when the tissue pre-fit changed the tissue, uncertainty.csv only when
  // the uncertainty could be computed.
  std::vector<std::string> files = {"cords.json", "tissue.json"};
  for (const std::string& name : closureOutputFiles(false)) files.push_back(name);
  files.insert(files.end(), {"convergence.csv", "convergence.svg", "uncertainty.csv",
                             "sections.svg", "report.md"});
  return files;
}

}  // namespace chordfit::cli
