#include <iostream>

#include "tools/command_support.h"
#include "tools/commands.h"

namespace chordfit::cli {

int runValidate(const ValidateOptions& options) {
  const auto valve_case = loadCaseOrReport(options.case_dir);
  if (!valve_case) return kExitBadInput;
  std::cout << caseSummary(*valve_case) << "valid\n";
  return kExitOk;
}

}  // namespace chordfit::cli
