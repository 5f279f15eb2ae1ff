// What `chordfit fit` writes besides the cord set and the closure: the convergence history
// (CSV, SVG), the per-parameter uncertainty (CSV) and report.md, with the counts of slack and
// determined cords that report.md, metrics.json and the summary line share.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/case_data.h"
#include "core/metrics.h"
#include "inverse/fit_cords.h"
#include "tools/commands.h"

namespace chordfit::cli {

// convergence.csv and convergence.svg (cost and AvgD against forward simulations).
std::string convergenceCsv(const std::vector<inverse::IterationRecord>& history);
std::string convergenceSvg(const std::vector<inverse::IterationRecord>& history,
                           const std::string& optimizer);

// uncertainty.csv: one row per parameter (fit.uncertainty must be ok()).
std::string uncertaintyCsv(const inverse::FitOutcome& fit);

// A PM tip offset (--params scales+tips) is determined by the tracings when it lies more than
// kTipOffsetDeterminedSds of its SD from 0 (about 95 % two-sided under the Jacobian's normal
// approximation); within that, zero fits as well. An offset at its --tip-box bound is not
// (the bound, not the tracings, holds it there; as for cords). Measured on the quick-start case:
// offsets within 1 SD moved the anterolateral tip from 0.87 to 4.23 mm off the true one.
constexpr double kTipOffsetDeterminedSds = 2.0;
bool tipOffsetDetermined(const inverse::FitOutcome& fit, std::size_t parameter);
// "PM tips: 2 of 6 tip offsets determined ...", or "" without tip parameters or uncertainty.
std::string tipOffsetsLine(const inverse::FitOutcome& fit);

// Cords slack in the fitted closure (closed span short of the fitted length, core/cordset.h).
int slackCords(const inverse::FitOutcome& fit);
// Cords whose fitted length the tracings pin down: rest-length SD below 3 % (the issue's
// recovery tolerance) and not at a bound; 0 without an uncertainty.
int identifiedCords(const inverse::FitOutcome& fit);
// Cords that are fit parameters (not locked).
int freeCords(const inverse::FitOutcome& fit);
// "16 extra closures", or "16 extra closures, 2 unsettled" when some reached the step cap.
std::string extraClosures(int closures, int unsettled);

// Prints the summary line of the locked-cord probe (inverse/locked_cord_probe.h), nothing
// when no cord is locked or the probe did not run: on stdout, or as a note (stderr) when a
// locked cord holds the fit back, i.e. unlocking it alone lowers the fit's data cost by at
// least kLockedCordNoteDrop.
constexpr double kLockedCordNoteDrop = 0.05;
void printLockedProbeSummary(const ValveCase& c, const FitCommandOptions& o,
                             const inverse::FitOutcome& fit);
// When the fit does not reconstruct a prolapse the tracings show (Table 1's last column),
// what to try, or "": cords all locked there ask to be unlocked; cords at the upper scale
// bound, a higher bound; otherwise, without --tissue-prefit, softer tissue (the benchmark's
// prolapse-P3 seeds 2-3 are reconstructed only with it: docs/fitting.md, "Tissue pre-fit").
// One line, ending in a newline, for report.md and (after "note: ") the terminal.
// Whether the optimiser evaluated any point of its own (a Ceres iteration or an NLopt
// evaluation in the main fit's history); false when the pre-fits left it too little budget.
bool optimiserRan(const inverse::FitOutcome& fit, const std::string& optimizer);
// "" when the optimiser ran; else "pre-fits only; ceres took no step" (a pre-fit ran) or "ceres
// took no step", for the messages and figures that would credit it with the result.
std::string optimiserNoStep(const inverse::FitOutcome& fit, const std::string& optimizer);

std::string missedProlapseHint(const ValveCase& c, const FitCommandOptions& o,
                               const inverse::FitOutcome& fit, const ValveMetrics& fit_metrics);
// When the fit ends at a higher cost than the seed as given, why, or "": the fit starts from
// the seed clamped into the bounds and returns the best point it saw inside them, so a seed
// outside the bounds can be better than every point the budget reached. One line, ending in a
// newline, for report.md and (after "note: ") the terminal.
std::string worseThanSeedNote(const inverse::FitOutcome& fit);
// What the tissue retry did (FitOptions::tissue_retry), for report.md and the terminal; and
// metrics.json's "tissue_retry" (docs/outputs.md).
// Why --tissue-prefit, asked for, did not run ("not run: --max-sims 80 leaves too few
// closures"), or "" when it ran or was not asked for.
std::string tissuePrefitNotRun(const inverse::FitOutcome& fit, const FitCommandOptions& o);
std::string tissueRetryLine(const inverse::FitOutcome& fit, const FitCommandOptions& o);
nlohmann::json tissueRetryJson(const inverse::FitOutcome& fit);
// metrics.json's "locked_cord_probe" (docs/outputs.md).
nlohmann::json lockedProbeJson(const ValveCase& c, const inverse::FitOutcome& fit);

// report.md: options, pre-fits, Table 1 rows seed vs fit, prolapse segments, the sections
// figure, and the per-cord table (lengths, closed span, SD, sensitivity, provenance).
std::string fitReport(const ValveCase& c, const FitCommandOptions& o,
                      const inverse::FitOutcome& fit, const ValveMetrics& seed_metrics,
                      const ValveMetrics& fit_metrics);

}  // namespace chordfit::cli
