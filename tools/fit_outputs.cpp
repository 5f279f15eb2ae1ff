#include "tools/fit_outputs.h"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/case_io.h"
#include "core/cordset_io.h"
#include "core/metrics.h"
#include "core/section_figure.h"
#include "core/simulator.h"
#include "inverse/fit_cords.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/fit_report.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

namespace {

constexpr const char* kSeedColour = "#9a9a9a";  // the seed closure in sections.svg

// --- Stage 6: the output files ---

// `chordfit simulate`'s options that close the fitted cords (on the fitted tissue, if any)
// into `out`, the staging directory.
SimulateOptions fittedClosureSimulation(const FitCommandOptions& o, const inverse::FitOutcome& fit,
                                        const std::filesystem::path& out) {
  SimulateOptions simulate;
  simulate.case_dir = o.case_dir;
  simulate.cords_file = (out / "cords.json").string();
  if (fit.tissue.size() > 0) simulate.tissue_file = (out / "tissue.json").string();
  simulate.out_dir = out.string();
  simulate.threads = o.threads;
  simulate.settings_overrides = o.settings_overrides;
  simulate.quiet = true;
  // sections.svg is writeFitFigures', with the seed closure beside the fitted one; the files
  // are listed once published (printFitSummary).
  simulate.sections = false;
  simulate.report_files = false;
  return simulate;
}

// Writes cords.json (and tissue.json) into `out`, then the fitted closure there as `chordfit
// simulate` writes it: closed.ply, closed.vtk and metrics.json. Returns runSimulate's exit
// code (its failure reported).
int writeFittedCordsAndClosure(const FitCommandOptions& o, const ValveCase& valve_case,
                               const inverse::FitOutcome& fit, const std::filesystem::path& out) {
  writeCordSet(out / "cords.json", fit.fitted, &valve_case.mesh);
  // The tissue the cords were fitted on, when the tissue pre-fit changed it; the closure
  // written next uses it too.
  if (fit.tissue.size() > 0) writeTissueFile(out / "tissue.json", fit.tissue);
  std::printf("fitted cords: full closure from the open state\n");
  return runSimulate(fittedClosureSimulation(o, fit, out));
}

// metrics.json's "uncertainty" (docs/outputs.md): the Jacobian's cost, and its result or why
// there is none.
nlohmann::json uncertaintyMetrics(const inverse::FitOutcome& fit) {
  nlohmann::json u = {{"jacobian_sims", fit.uncertainty.jacobian_sims},
                      {"unsettled_sims", fit.uncertainty.unsettled_sims},
                      {"seconds", fit.uncertainty_seconds}};
  if (fit.uncertainty.ok()) {
    u["residual_sd_mm"] = fit.uncertainty.sigma_mm;
    u["correlation_time"] = fit.uncertainty.correlation_time;
    u["identified_cords"] = identifiedCords(fit);
    u["free_cords"] = freeCords(fit);
  } else {
    u["error"] = fit.uncertainty.error.empty() ? "no free parameters" : fit.uncertainty.error;
  }
  return u;
}

// Adds the pre-fits' keys to metrics.json: whether each ran and what it changed.
void addPrefitMetrics(nlohmann::json& metrics, const inverse::FitOutcome& fit) {
  // Whether the cord pre-fits ran (options.prefit says only that they were asked for), and
  // why not when they were skipped.
  metrics["prefit_ran"] = fit.prefit_ran;
  metrics["prefit_kind_ran"] = fit.prefit_kind_stage == inverse::KindStage::kRan;
  metrics["segment_prefit_ran"] = fit.segment_prefit_ran;
  metrics["tissue_prefit_ran"] = fit.tissue_prefit_ran;
  if (!fit.prefit_skipped.empty()) metrics["prefit_skipped"] = fit.prefit_skipped;
  metrics["prefit_factor"] = fit.prefit_factor;
  metrics["prefit_primary_factor"] = fit.prefit_primary_factor;
  metrics["prefit_secondary_factor"] = fit.prefit_secondary_factor;
  metrics["segment_prefit"] = fit.segment_prefit_changes;
  metrics["tissue_prefit"] = fit.tissue_prefit_changes;
  metrics["tissue_retry"] = tissueRetryJson(fit);
  const inverse::SlackReleaseOutcome& release = fit.slack_release;
  metrics["slack_release"] = {{"proposed_cords", release.proposal.cords.size()},
                              {"kept", release.kept},
                              {"primary_reference", release.proposal.primary_reference},
                              {"secondary_reference", release.proposal.secondary_reference}};
}

// Adds the options the fit ran with to metrics.json.
void addRunOptionMetrics(nlohmann::json& metrics, const FitCommandOptions& o) {
  metrics["distance"] = o.distance;  // the data residual the fit minimised
  metrics["section_weight"] = o.section_weight;
  metrics["tip_weight"] = o.tip_weight;
  metrics["scale_bounds"] = o.scale_bounds;
  // How the fit was run, so that two results can be told apart by their files alone.
  metrics["options"] = {{"prefit", o.prefit},
                        {"tissue_prefit", o.tissue_prefit},
                        {"tissue_retry", o.tissue_retry},
                        {"slack_release", o.slack_release},
                        {"tip_box_mm", o.tip_box_mm},
                        {"fd_step", o.fd_scale_step},
                        {"fd_tip_step_mm", o.fd_tip_step_mm},
                        {"fd_warm", o.fd_warm_start},
                        {"fd_slack_closures", o.fd_slack_closures},
                        {"uncertainty", o.uncertainty}};
}

// Adds the fit's keys (docs/outputs.md) to `metrics`, the closure's metrics.json as simulate
// wrote it.
void addFitMetrics(nlohmann::json& metrics, const FitCommandOptions& o, const ValveCase& valve_case,
                   const inverse::FitOutcome& fit) {
  metrics["optimizer"] = o.optimizer;
  metrics["params"] = o.params;
  metrics["parameters"] = fit.x.size();
  metrics["forward_sims"] = fit.forward_sims + 1;  // + the closure just written
  metrics["unsettled_sims"] = fit.unsettled_sims;  // of the fit's runs (not the one written)
  metrics["fit_seconds"] = fit.seconds;
  metrics["initial_mean_mm"] = fit.seed_evaluation.mean_deviation_mm;
  metrics["initial_cost"] = fit.seed_evaluation.cost;
  metrics["final_cost"] = fit.final_evaluation.cost;
  addPrefitMetrics(metrics, fit);
  addRunOptionMetrics(metrics, o);
  // With --fd-warm: whether Ceres gave warm-started differences up for full closures.
  if (o.fd_warm_start) metrics["fd_switched_to_full_closures"] = fit.switched_to_full_closures;
  if (o.uncertainty) metrics["uncertainty"] = uncertaintyMetrics(fit);
  if (!fit.locked_probes.cords.empty())
    metrics["locked_cord_probe"] = lockedProbeJson(valve_case, fit);
  metrics["slack_cords"] = slackCords(fit);
  metrics["termination"] = fit.termination;
  metrics["threads"] = o.threads;
}

// Rewrites `out`/metrics.json with the fit's keys added. Returns false, reported, when the
// file cannot be read back.
bool extendMetricsFile(const std::filesystem::path& out, const FitCommandOptions& o,
                       const ValveCase& valve_case, const inverse::FitOutcome& fit) {
  std::string metrics_text;
  if (!readWholeFile(out / "metrics.json", metrics_text)) {
    std::cerr << "error: fit: cannot read back " << (out / "metrics.json").string() << "\n";
    return false;
  }
  nlohmann::json metrics = nlohmann::json::parse(metrics_text);
  addFitMetrics(metrics, o, valve_case, fit);
  writeFileAtomically(out / "metrics.json", metrics.dump(2) + "\n");
  return true;
}

// Writes into `out` what the fit adds to the closure's files: convergence.csv and .svg,
// uncertainty.csv (when computed), report.md and sections.svg (the seed closure beside the
// fitted one).
void writeFitFigures(const std::filesystem::path& out, const FitCommandOptions& o,
                     const ValveCase& valve_case, const inverse::FitOutcome& fit,
                     const ValveMetrics& seed_metrics, const ValveMetrics& fit_metrics) {
  writeFileAtomically(out / "convergence.csv", convergenceCsv(fit.history));
  if (fit.uncertainty.ok()) writeFileAtomically(out / "uncertainty.csv", uncertaintyCsv(fit));
  // Figures name the method that made the result: the pre-fits' when the optimiser took no step.
  const std::string no_step = optimiserNoStep(fit, o.optimizer);
  const std::string method = no_step.empty() ? o.optimizer : no_step;
  writeFileAtomically(out / "convergence.svg", convergenceSvg(fit.history, method));
  writeFileAtomically(out / "report.md", fitReport(valve_case, o, fit, seed_metrics, fit_metrics));
  writeFileAtomically(
      out / "sections.svg",
      caseSectionFigureSvg(valve_case,
                           {{"seed closure", fit.seed_evaluation.closed_V, kSeedColour, true, 1.4},
                            {"fitted closure", fit.final_evaluation.closed_V, "", false, 2.0}},
                           {valve_case.name + ": seed and fitted closures against the tracings (" +
                            method + ", " + o.params + ")"}));
}

}  // namespace

// Stage 6 (fit_outputs.h).
WrittenFit writeFitOutputs(const FitCommandOptions& o, const ValveCase& valve_case,
                           const inverse::FitOutcome& fit) {
  WrittenFit written;
  StagedOutput staged(o.out_dir, fitOutputFiles(), {}, "fit");
  const std::filesystem::path& out = staged.dir();
  written.exit_code = writeFittedCordsAndClosure(o, valve_case, fit, out);
  if (written.exit_code != kExitOk) return written;
  written.seed_metrics = computeMetrics(valve_case, fit.seed_evaluation.closed_V);
  written.fit_metrics = computeMetrics(valve_case, fit.final_evaluation.closed_V);
  if (!extendMetricsFile(out, o, valve_case, fit)) {
    written.exit_code = kExitFailure;
    return written;
  }
  writeFitFigures(out, o, valve_case, fit, written.seed_metrics, written.fit_metrics);
  written.published = staged.publish();
  return written;
}

}  // namespace chordfit::cli
