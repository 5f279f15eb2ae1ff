#include <iostream>

#include "tools/command_support.h"
#include "tools/commands.h"

namespace chordfit::cli {

int runValidate(const ValidateOptions& options) {
  auto valve_case = loadCaseOrReport(options.case_dir);
  if (!valve_case) return kExitBadInput;
  // The simulator overrides too: simulate and fit would reject them.
  if (!caseSettingsOrReport(*valve_case, options.case_dir, SettingsUse::kCheck))
    return kExitBadInput;
  std::cout << caseSummary(*valve_case) << "valid\n";
  return kExitOk;
}

}  // namespace chordfit::cli
