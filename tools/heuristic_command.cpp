#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <utility>

#include "core/cordset_io.h"
#include "core/counted.h"
#include "core/heuristic.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

namespace {

void printCordSummary(const CordSet& set, const ValveMesh& mesh) {
  for (const PmTip& tip : set.tips) {
    std::printf("  tip %-14s at (%7.2f, %7.2f, %7.2f) mm\n", tip.name.c_str(), tip.position.x(),
                tip.position.y(), tip.position.z());
  }
  struct GroupStats {
    int primary = 0, secondary = 0;
    double length_sum = 0.0;
  };
  std::map<std::string, GroupStats> groups;
  for (const Cord& cord : set.cords) {
    GroupStats& g = groups[groupName(cord, mesh.leaflet, mesh.leaflet_names, set.tips)];
    (cord.kind == CordKind::kPrimary ? g.primary : g.secondary) += 1;
    g.length_sum += cord.rest_length;
  }
  std::printf("  %-30s %8s %10s %16s\n", "group (leaflet/tip)", "primary", "secondary",
              "mean l0 (mm)");
  for (const auto& [name, g] : groups) {
    std::printf("  %-30s %8d %10d %16.2f\n", name.c_str(), g.primary, g.secondary,
                g.length_sum / (g.primary + g.secondary));
  }
}

// Notes for what a coarse placement leaves without a cord (--primary-spacing 60 on the
// parametric valve placed two cords, both on the anterior leaflet, and printed the
// posteromedial tip at the annulus centre without a word). A leaflet without a cord billows
// into the atrium in systole; a tip without a cord pulls nothing, and the paper's formula,
// a centroid of its insertions, has none to place it by.
void noteWhatNoCordHolds(const CordSet& set, const ValveMesh& mesh, bool placed, bool tips_given,
                         const HeuristicCommandOptions& options) {
  if (placed) {
    for (std::size_t leaflet = 0; leaflet < mesh.leaflet_names.size(); ++leaflet) {
      const bool held = std::any_of(set.cords.begin(), set.cords.end(), [&](const Cord& c) {
        return mesh.leaflet(c.vertex) == static_cast<int>(leaflet);
      });
      if (!held)
        printNote(
            "heuristic: the %s leaflet gets no cord at --primary-spacing %g mm "
            "and --secondary-spacing %g mm: nothing holds it down in systole\n",
            mesh.leaflet_names[leaflet].c_str(), options.primary_spacing_mm,
            options.secondary_spacing_mm);
    }
  }
  for (std::size_t t = 0; t < set.tips.size(); ++t) {
    const bool used = std::any_of(set.cords.begin(), set.cords.end(),
                                  [&](const Cord& c) { return c.tip == static_cast<int>(t); });
    if (!used)
      printNote("heuristic: tip %s carries no cord%s\n", set.tips[t].name.c_str(),
                tips_given ? ""
                           : " (none of the cords lies on its side), so its position, the "
                             "paper's centroid of its insertions, is a placeholder");
  }
}
}  // namespace

int runHeuristic(const HeuristicCommandOptions& options) {
  if (!optionsArePositive("heuristic",
                          {{"--primary-spacing", options.primary_spacing_mm},
                           {"--secondary-spacing", options.secondary_spacing_mm},
                           {"--secondary-depth", options.secondary_depth_mm}},
                          "a positive length in mm"))
    return kExitBadInput;
  // A spacing finer than any mesh's edges places no more cords (heuristic.h,
  // kMinCordSpacingMm); far finer, its count of targets used to overflow.
  for (const auto& [option, spacing] :
       {std::pair{"--primary-spacing", options.primary_spacing_mm},
        std::pair{"--secondary-spacing", options.secondary_spacing_mm}}) {
    if (spacing < kMinCordSpacingMm) {
      std::cerr << "error: heuristic: " << option << ": must be at least " << kMinCordSpacingMm
                << " mm (finer than the mesh's edges places no more cords), got " << spacing
                << "\n";
      return kExitBadInput;
    }
  }
  for (const auto& [option, compliance] :
       {std::pair{"--primary-compliance", options.primary_compliance},
        std::pair{"--secondary-compliance", options.secondary_compliance}}) {
    if (!(compliance >= 0.0 && compliance <= kMaxCordComplianceMmPerN)) {
      std::cerr << "error: heuristic: " << option << ": must be in [0, " << kMaxCordComplianceMmPerN
                << "] mm/N, got " << compliance << "\n";
      return kExitBadInput;
    }
  }
  const auto valve_case = loadCaseOrReport(options.case_dir);
  if (!valve_case) return kExitBadInput;
  // heuristicCordSet would ignore such pm_tips without a word and place the tips by the formula.
  if (const std::string problem = pmTipsCountProblem(*valve_case); !problem.empty()) {
    std::cerr << "error: heuristic: " << options.case_dir << ": pm_tips: " << problem
              << "; give pm_tips the cord set's tips in its order, or leave pm_tips out of "
                 "case.json (the paper's formula then places them)\n";
    return kExitBadInput;
  }
  const bool case_cords = valve_case->cords && !valve_case->cords->cords.empty();
  if ((options.primary_compliance > 0.0 || options.secondary_compliance > 0.0) && case_cords)
    printNote(
        "heuristic: the case's own cords keep their compliance; "
        "--primary-compliance and --secondary-compliance apply to placed cords\n");
  // The placement options were taken without a word on a case whose cords are placed already.
  const HeuristicCommandOptions defaults;
  if (case_cords && (options.primary_spacing_mm != defaults.primary_spacing_mm ||
                     options.secondary_spacing_mm != defaults.secondary_spacing_mm ||
                     options.secondary_depth_mm != defaults.secondary_depth_mm))
    printNote(
        "heuristic: the case's own cords keep their insertions (the heuristic "
        "gives them tips and rest lengths); --primary-spacing, --secondary-spacing and "
        "--secondary-depth apply when it places the cords\n");
  HeuristicOptions heuristic;
  heuristic.primary_spacing_mm = options.primary_spacing_mm;
  heuristic.secondary_spacing_mm = options.secondary_spacing_mm;
  heuristic.secondary_depth_mm = options.secondary_depth_mm;
  heuristic.primary_compliance_mm_per_n = options.primary_compliance;
  heuristic.secondary_compliance_mm_per_n = options.secondary_compliance;
  const CordSet set = heuristicCordSet(*valve_case, heuristic);
  if (set.cords.empty()) {
    std::cerr << "error: " << options.case_dir
              << ": cords: the heuristic placed no cords (no free edge found?)\n";
    return kExitBadInput;
  }
  const bool any_secondary = std::any_of(set.cords.begin(), set.cords.end(), [](const Cord& c) {
    return c.kind == CordKind::kSecondary;
  });
  if (!case_cords && !any_secondary)
    printNote(
        "heuristic: no secondary cord placed: no leaflet vertex lies "
        "--secondary-depth %g mm (along mesh edges) in from the free edge and %g mm or "
        "more from the annulus\n",
        options.secondary_depth_mm, HeuristicOptions{}.min_annulus_distance_mm);
  noteWhatNoCordHolds(set, valve_case->mesh, !case_cords,
                      valve_case->tips && valve_case->tips->size() == set.tips.size(), options);
  writeCordSet(options.out_file, set, &valve_case->mesh);
  forgetPublished(options.out_file);  // now the user's file (staged_output.h)
  std::cout << "heuristic cord set: " << counted(set.cords.size(), "cord") << " on "
            << counted(set.tips.size(), "PM tip") << " -> " << options.out_file << "\n";
  printCordSummary(set, valve_case->mesh);
  return kExitOk;
}

}  // namespace chordfit::cli
