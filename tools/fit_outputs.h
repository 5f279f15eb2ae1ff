// chordfit fit's output files (stage 6 of runFit, tools/fit_command.cpp): the fitted cords and
// their closure through the simulate command's code path, metrics.json extended with the fit's
// keys, the convergence, uncertainty, report and section figure, published together into --out.
#pragma once

#include "core/metrics.h"
#include "inverse/fit_cords.h"
#include "tools/commands.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

// What writeFitOutputs leaves for the summary.
struct WrittenFit {
  int exit_code = kExitOk;  // otherwise the failure was reported and nothing was published
  StagedOutput::Published published;
  ValveMetrics seed_metrics, fit_metrics;
};

// Stage 6. Writes every output file into a staging directory and publishes them into --out
// together (staged_output.h). On failure (reported) the exit code is set and --out is left
// as it was; exceptions (a failed write) propagate, as from every command, to main.
WrittenFit writeFitOutputs(const FitCommandOptions& o, const ValveCase& valve_case,
                           const inverse::FitOutcome& fit);

}  // namespace chordfit::cli
