#include <iostream>
#include <string>

#include "core/counted.h"
#include "core/heuristic.h"
#include "tools/command_support.h"
#include "tools/commands.h"

namespace chordfit::cli {

namespace {

// Which tips the commands use when the case gives both pm_tips and cords, or "": a user who
// gives pm_tips beside cords expects simulate and fit to use them, and they do not (they close
// the case's cords, which hang from the cord set's own tips: resolveCords); only the heuristic
// reads them (heuristicCordSet), and only when the counts match (pmTipsCountProblem).
std::string pmTipsBesideCordsNote(const ValveCase& valve_case) {
  if (!valve_case.tips || !valve_case.cords || valve_case.cords->cords.empty()) return "";
  std::string note =
      "note: case.json: pm_tips and cords are both given: simulate, fit, sweep-cord, compare and "
      "edit-cords take the cords with the cord set's own tips and do not read pm_tips; only "
      "`chordfit heuristic` uses it, giving each cord-set tip the position (and name) of the "
      "pm_tips tip in the same place in the list";
  if (!pmTipsCountProblem(valve_case).empty())
    note += ". Here there are " + counted(valve_case.tips->size(), "PM tip") +
            " for the cord set's " + counted(valve_case.cords->tips.size(), "tip") +
            ": `chordfit heuristic` refuses the case";
  return note + "\n";
}

}  // namespace

int runValidate(const ValidateOptions& options) {
  auto valve_case = loadCaseOrReport(options.case_dir);
  if (!valve_case) return kExitBadInput;
  // The simulator overrides too: simulate and fit would reject them.
  if (!caseSettingsOrReport(*valve_case, options.case_dir, SettingsUse::kCheck))
    return kExitBadInput;
  std::cout << caseSummary(*valve_case);
  printLinesToStderr(pmTipsBesideCordsNote(*valve_case));
  printLinesToStderr(duplicateTracingsNote(*valve_case));
  std::cout << "valid\n";
  return kExitOk;
}

}  // namespace chordfit::cli
