// chordfit fit's inputs (stages 1 and 2 of runFit, tools/fit_command.cpp): the option values
// checked before any file is read, then the case, the seed cords and the closure settings
// checked against the options. Each refusal is reported on stderr, naming the option or file.
#pragma once

#include <optional>

#include "core/case_data.h"
#include "core/cordset.h"
#include "core/simulator.h"
#include "inverse/fit_parameters.h"
#include "tools/commands.h"

namespace chordfit::cli {

struct FitInputs {
  ValveCase valve_case;
  CordSet seed;
  SimulationSettings settings;
};

// Stage 1. The parameter mode of the fit when every option value that needs no input file is
// acceptable; otherwise nullopt, after reporting the first refused value in the order below.
std::optional<inverse::ParameterMode> checkOptionValues(const FitCommandOptions& o);

// Stage 2. The case, the seed and the closure settings when they load and suit the options
// (`mode` from checkOptionValues); otherwise nullopt, after reporting the first problem.
std::optional<FitInputs> loadFitInputs(const FitCommandOptions& o, inverse::ParameterMode mode);

}  // namespace chordfit::cli
