// chordfit compare: "manual vs optimised" (issue 5 item 6). Closes the case once per cord set
// and lays the results side by side in the paper's Table 1 format (Markdown) plus a CSV with
// the prolapse segments and the solver outcome. Every input is checked before the first
// simulation, and nothing is written unless every simulation succeeded.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/case_io.h"
#include "core/closure_model.h"
#include "core/counted.h"
#include "core/enface_figure.h"
#include "core/metrics.h"
#include "core/parallel_for.h"
#include "core/section_figure.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/in_order_progress.h"
#include "tools/staged_output.h"
#include "tools/truth_recovery.h"

namespace chordfit::cli {

namespace {

struct ComparedSet {
  std::string label;
  std::string file;
  CordSet cords;
  ValveCase valve_case;  // the case, with this set's tissue
  ValveMetrics metrics;
  bool converged = false;
  int steps = 0;
  Eigen::MatrixXd closed_V;
  std::optional<TruthRecovery> recovery;  // against the case's truth, when it has one
};

// One colour per cord set in sections.svg (colour-blind safe, Okabe and Ito 2008). The first
// four are none of the leaflet colours of fit's and simulate's sections.svg (blue anterior,
// green posterior: a "heuristic" in the anterior blue and a "fit" in the posterior green read
// as leaflets beside them), and black only third (the tracing points are black rings); the
// orange last: the closed annulus hinges are orange.
const char* const kSetColours[] = {"#cc79a7", "#d55e00", "#000000", "#56b4e9",
                                   "#0072b2", "#009e73", "#e69f00"};

std::string sectionsSvg(const ValveCase& c, const std::vector<ComparedSet>& sets) {
  std::vector<SectionLayer> layers;
  for (std::size_t i = 0; i < sets.size(); ++i) {
    // Past the seventh set the colours come round again, dashed (past the fourteenth, solid
    // again: compare more sets than that and two of them look alike).
    const std::size_t colours = std::size(kSetColours);
    layers.push_back(
        {sets[i].label, sets[i].closed_V, kSetColours[i % colours], (i / colours) % 2 == 1, 1.8});
  }
  const std::string title =
      "Cord sets compared on case " + c.name + ": closed valves against the tracings";
  return caseSectionFigureSvg(c, layers, {title});
}

std::vector<std::string> splitLabels(const std::string& text) {
  std::vector<std::string> labels;
  std::string label;
  std::istringstream in(text);
  while (std::getline(in, label, ',')) labels.push_back(label);
  if (!text.empty() && text.back() == ',') labels.push_back("");
  return labels;
}

// Labels name table rows: one per cord file, non-empty, unique, and free of the characters
// that would break a Markdown or CSV row. Without --labels they are the file names, and a
// problem is the files' (a file given twice), not that of an option the user did not give.
bool checkLabels(const std::vector<std::string>& labels, std::size_t files, bool defaulted) {
  if (labels.size() != files) {
    std::cerr << "error: compare: --labels: " << labels.size() << " label(s) for " << files
              << " cord file(s); give one label per file\n";
    return false;
  }
  const char* source = defaulted ? "CORDS" : "--labels";
  const char* hint =
      defaulted ? " (without --labels the file names label the rows; give --labels)" : "";
  std::set<std::string> seen;
  for (const std::string& label : labels) {
    if (label.empty() || label.find_first_of("|\"\n") != std::string::npos) {
      std::cerr << "error: compare: " << source << ": \"" << label
                << "\": labels must be non-empty and contain no '|', '\"' or newline" << hint
                << "\n";
      return false;
    }
    if (!seen.insert(label).second) {
      std::cerr << "error: compare: " << source << ": \"" << label
                << (defaulted ? "\" is given twice" : "\" appears twice") << hint << "\n";
      return false;
    }
  }
  return true;
}

std::string csvNumber(double value, const char* format = "%.6f") {
  if (!std::isfinite(value)) return "";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

// Segments joined by spaces ("A2 P2"), empty when none: one CSV cell without quoting.
std::string segmentCell(const std::vector<std::string>& segments) {
  std::string cell;
  for (const std::string& s : segments) cell += (cell.empty() ? "" : " ") + s;
  return cell;
}

std::string csvQuoted(const std::string& text) {
  std::string quoted = "\"";
  for (char c : text) quoted += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// A number for a CSV cell, empty when it is not finite (no taut cord, tips not compared).
std::string finiteCell(double value, const char* format) {
  return std::isfinite(value) ? csvNumber(value, format) : "";
}

std::string recoveryCsvCells(const std::optional<TruthRecovery>& r) {
  if (!r || !r->problem.empty()) return ",,";
  return finiteCell(r->median_error_pct, "%.3f") + "," +
         finiteCell(r->median_error_taut_pct, "%.3f") + "," +
         finiteCell(r->max_tip_offset_mm, "%.3f");
}

// "4.9 % (32 cords), taut 2.6 % (8), tips ≤ 1.23 mm off", or why the set was not compared.
std::string recoveryText(const TruthRecovery& r) {
  if (!r.problem.empty()) return "not compared: " + r.problem;
  char text[160];
  std::snprintf(text, sizeof text, "%.1f %% (%d cords)", r.median_error_pct, r.cords);
  std::string line = text;
  if (r.taut_cords > 0) {
    std::snprintf(text, sizeof text, ", taut in the truth %.1f %% (%d)", r.median_error_taut_pct,
                  r.taut_cords);
    line += text;
  } else {
    line += ", none taut in the truth";
  }
  if (std::isfinite(r.max_tip_offset_mm)) {
    std::snprintf(text, sizeof text, ", tips at most %.2f mm off%s", r.max_tip_offset_mm,
                  r.heuristic_tips ? " (the heuristic's, not moved)" : "");
    line += text;
  }
  return line;
}

std::string compareCsv(const std::vector<ComparedSet>& sets) {
  std::string csv =
      "label,cords_file,area_mm2,min_mm,median_mm,max_mm,mean_mm,sd_mm,prolapse_reconstructed,"
      "section_prolapse_segments,prolapse_segments,tracing_prolapse_segments,converged,steps,"
      "recovery_median_pct,recovery_median_pct_taut,max_tip_offset_mm,orifice_coverage,"
      "open_orifice_area_mm2,self_intersections\n";
  for (const ComparedSet& s : sets) {
    const ValveMetrics& m = s.metrics;
    const DeviationStats& d = m.deviation;
    const bool t = m.has_tracings;
    csv += csvQuoted(s.label) + "," + csvQuoted(s.file) + "," + csvNumber(m.area_mm2, "%.3f") +
           "," + (t ? csvNumber(d.min) : "") + "," + (t ? csvNumber(d.median) : "") + "," +
           (t ? csvNumber(d.max) : "") + "," + (t ? csvNumber(d.mean) : "") + "," +
           (t ? csvNumber(d.sd) : "") + "," + (t ? (m.prolapse_reconstructed ? "yes" : "no") : "") +
           "," + (t ? segmentCell(m.section_prolapse.segments) : "") + "," +
           segmentCell(m.mesh_prolapse.segments) + "," +
           (t ? segmentCell(m.tracing_prolapse.segments) : "") + "," +
           (s.converged ? "yes" : "no") + "," + std::to_string(s.steps) + "," +
           recoveryCsvCells(s.recovery) + "," + finiteCell(m.orifice.coverage(), "%.4f") + "," +
           csvNumber(m.orifice.open_area_mm2, "%.1f") + "," + std::to_string(m.self_intersections) +
           "\n";
  }
  return csv;
}

// One row per cord and set (long format, any cord counts): the set's rest length and, on a
// synthetic case whose truth pairs with the set, the true length and the signed error.
std::string cordsCsv(const ValveCase& c, const std::vector<ComparedSet>& sets,
                     const std::optional<CaseTruth>& truth) {
  std::string csv =
      "label,cord,group,kind,rest_length_mm,scale,provenance,locked,true_rest_length_mm,"
      "error_pct,taut_in_truth\n";
  for (const ComparedSet& s : sets) {
    const bool paired = s.recovery && s.recovery->problem.empty();
    for (std::size_t i = 0; i < s.cords.cords.size(); ++i) {
      const Cord& cord = s.cords.cords[i];
      csv += csvQuoted(s.label) + "," + std::to_string(i) + "," +
             csvQuoted(groupName(cord, c.mesh.leaflet, c.mesh.leaflet_names, s.cords.tips)) + "," +
             toString(cord.kind) + "," + csvNumber(cord.rest_length) + "," +
             csvNumber(cord.scale()) + "," + toString(cord.provenance) + "," +
             (cord.locked ? "yes" : "no") + ",";
      if (paired) {
        const TrueCord& t = truth->cords[i];
        csv += (t.ruptured ? std::string() : csvNumber(t.rest_length_mm)) + "," +
               finiteCell(s.recovery->signed_error_pct[i], "%.3f") + "," + (t.taut ? "yes" : "no");
      } else {
        csv += ",,";
      }
      csv += "\n";
    }
  }
  return csv;
}

// compare.md's per-cord table against the truth: each set's length and signed error, side
// by side ("manual vs optimised" per cord). Only when every set pairs with the truth.
std::string perCordTruthTable(const ValveCase& c, const std::vector<ComparedSet>& sets,
                              const CaseTruth& truth) {
  for (const ComparedSet& s : sets)
    if (!s.recovery || !s.recovery->problem.empty()) return "";
  std::string md =
      "\nPer cord: each set's rest length (mm) and its error against the true length. Taut: "
      "under tension in the true closed valve; a cord slack there is bounded by the tracings "
      "from below only, so its error says little about a fit.\n\n| Cord | Group | Kind | True "
      "(mm) | Taut in the truth |";
  std::string rule = "|---:|---|---|---:|---|";
  for (const ComparedSet& s : sets) {
    md += " " + s.label + " |";
    rule += "---:|";
  }
  md += "\n" + rule + "\n";
  const CordSet& first = sets.front().cords;
  for (std::size_t i = 0; i < truth.cords.size(); ++i) {
    const TrueCord& t = truth.cords[i];
    char cell[64];
    std::snprintf(cell, sizeof cell, "%.2f", t.rest_length_mm);
    md += "| " + std::to_string(i) + " | " +
          groupName(first.cords[i], c.mesh.leaflet, c.mesh.leaflet_names, first.tips) + " | " +
          toString(first.cords[i].kind) + " | " + (t.ruptured ? "ruptured" : cell) + " | " +
          (t.taut ? "yes" : "no") + " |";
    for (const ComparedSet& s : sets) {
      const double error = s.recovery->signed_error_pct[i];
      if (std::isfinite(error))
        std::snprintf(cell, sizeof cell, " %.2f (%+.1f %%) |", s.cords.cords[i].rest_length, error);
      else
        std::snprintf(cell, sizeof cell, " %.2f |", s.cords.cords[i].rest_length);
      md += cell;
    }
    md += "\n";
  }
  return md;
}

// "noise floor ...": what the truth itself reaches against the tracings, or "" when unknown.
std::string noiseFloorLine(const std::optional<CaseTruth>& truth) {
  if (!truth || !std::isfinite(truth->noise_floor_mm)) return "";
  char line[200];
  std::snprintf(line, sizeof line,
                "noise floor: the true cords closed on the truth's finer mesh reach AvgD %.2f mm "
                "(truth/metrics.json); closed on this case's mesh they may not.\n",
                truth->noise_floor_mm);
  return line;
}

// "97.9 % (12)": the closed valve's orifice coverage seen en face and its open area.
std::string coverageCell(const OrificeCoverage& orifice) {
  char text[64];
  std::snprintf(text, sizeof text, "%.1f %% (%.0f)", 100.0 * orifice.coverage(),
                orifice.open_area_mm2);
  return text;
}

std::string compareMarkdown(const ValveCase& c, const std::vector<ComparedSet>& sets,
                            const std::vector<std::string>& settings_overrides,
                            const std::optional<CaseTruth>& truth) {
  std::string md = "# Cord sets compared on case " + c.name + "\n\n";
  md += "Each cord set closed with the case's solver settings (`chordfit compare`)";
  if (!settings_overrides.empty()) {
    md += " and `--set`";
    for (const std::string& item : settings_overrides) md += " `" + item + "`";
  }
  md += "; deviations from the tracings in mm.\n\n";
  md += table1Header("Cord set");
  for (const ComparedSet& s : sets) md += table1Row(s.label, s.metrics);
  if (const std::string floor = noiseFloorLine(truth); !floor.empty()) md += "\nThe " + floor;
  md +=
      "\n| Cord set | File | Prolapse (tracings) | Prolapse (mesh, tracing planes) | Prolapse "
      "(mesh tissue) | Orifice covered (open mm²) | Converged (steps) |\n"
      "|---|---|---|---|---|---|---|\n";
  for (const ComparedSet& s : sets) {
    const ValveMetrics& m = s.metrics;
    const std::string none = "– (no tracings)";
    md += "| " + s.label + " | `" + s.file + "` | " +
          (m.has_tracings ? joinSegments(m.tracing_prolapse.segments) : none) + " | " +
          (m.has_tracings ? joinSegments(m.section_prolapse.segments) : none) + " | " +
          joinSegments(m.mesh_prolapse.segments) + " | " + coverageCell(m.orifice) + " | " +
          (s.converged ? "yes" : "no") + " (" + std::to_string(s.steps) + ") |\n";
  }
  if (sets.front().recovery) {
    md +=
        "\nAgainst the case's truth (`truth/truth.json`): median |rest length / true − 1| over "
        "the unruptured cords and over those taut in the true closed valve; each PM tip's "
        "distance from its true position.\n\n| Cord set | Rest-length error |\n|---|---|\n";
    for (const ComparedSet& s : sets)
      md += "| " + s.label + " | " + recoveryText(*s.recovery) + " |\n";
    md += perCordTruthTable(c, sets, *truth);
  }
  return md;
}

// The atrial view of the k-th cord set given (1-based): enface_<k>.svg.
constexpr const char* kEnfacePrefix = "enface_";
constexpr const char* kEnfaceSuffix = ".svg";
std::string enfaceFigureName(std::size_t k) {
  return kEnfacePrefix + std::to_string(k) + kEnfaceSuffix;
}

// enface_K.svg files in out_dir with K > count: an earlier compare of more cord sets wrote
// them, and beside this run's figures they would read as its own.
std::vector<std::string> enfaceFiguresBeyond(const std::string& out_dir, std::size_t count) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(out_dir, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string prefix = kEnfacePrefix, suffix = kEnfaceSuffix;
    if (name.size() <= prefix.size() + suffix.size() || name.rfind(prefix, 0) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const std::string digits =
        name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9 ||
        digits[0] == '0')
      continue;
    if (static_cast<std::size_t>(std::stoul(digits)) > count) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

// Closes every set, up to options.threads at a time; each writes only its own slot, so the
// results (and every output) are the same for any thread count. The progress lines come in
// the order given: a finished set is printed once every set before it is. A failed closure
// stops the sets after it (parallelFor), and the lowest failed set is reported, as with one
// thread. Returns kExitOk or the failure's exit code.
int closeSets(const ValveCase& valve_case, SimulationSettings settings,
              const CompareOptions& options, std::vector<ComparedSet>& sets) {
  const int count = static_cast<int>(sets.size());
  const int workers = std::max(1, std::min(options.threads, count));
  // Threads no set takes go into the closures themselves (bit-identical for any count).
  settings.threads = std::max(settings.threads, options.threads / workers);
  std::vector<SimulationResult> results(count);
  InOrderProgress progress(count, [&](int i) {
    const ComparedSet& s = sets[i];
    const SimulationResult& closed = results[i];
    if (!closed.ok()) return false;  // nothing after a failure is printed
    char avgd[64] = "no tracings";
    if (s.metrics.has_tracings)
      std::snprintf(avgd, sizeof avgd, "AvgD %.2f mm", s.metrics.deviation.mean);
    std::fprintf(stderr, "compare: [%d/%d] %s: %s after %d steps, %.1f s, %s\n", i + 1, count,
                 s.label.c_str(), closed.converged ? "converged" : "NOT converged (step cap)",
                 closed.steps, closed.seconds, avgd);
    return true;
  });
  struct ClosureFailed {};
  const auto closeSet = [&](int i) {
    ComparedSet& s = sets[i];
    if (!options.quiet) {
      progress.say([&] {
        std::fprintf(stderr, "compare: [%d/%d] %s: closing with %s\n", i + 1, count,
                     s.label.c_str(), counted(s.cords.cords.size(), "cord").c_str());
      });
    }
    SimulationResult& closed = results[i];
    closed = simulateClosure(s.valve_case, s.cords, settings);
    if (closed.ok()) {
      s.metrics = computeMetrics(valve_case, closed.V);
      s.converged = closed.converged;
      s.steps = closed.steps;
      s.closed_V = closed.V;
    }
    if (!options.quiet) progress.finished(i);
    if (!closed.ok()) throw ClosureFailed{};
  };
  try {
    parallelFor(count, workers, closeSet);
  } catch (const ClosureFailed&) {
    // Reported below, from the lowest set that failed.
  }
  for (int i = 0; i < count; ++i)
    if (!results[i].ok())
      return reportClosureFailure(results[i], sets[i].file, " (nothing written)");
  return kExitOk;
}

}  // namespace

std::vector<std::string> compareInputFiles(const CompareOptions& options) {
  std::vector<std::string> files = options.cords_files;
  if (!options.tissues.empty())
    for (const std::string& tissue : splitLabels(options.tissues))
      if (tissue != "-") files.push_back(tissue);
  return files;
}

int runCompare(const CompareOptions& options) {
  if (options.cords_files.empty()) {
    std::cerr << "error: compare: give at least one cord set file after CASE_DIR\n";
    return kExitBadInput;
  }
  std::vector<std::string> labels =
      options.labels.empty() ? options.cords_files : splitLabels(options.labels);
  if (!checkLabels(labels, options.cords_files.size(), options.labels.empty()))
    return kExitBadInput;

  auto valve_case = loadCaseOrReport(options.case_dir);
  if (!valve_case) return kExitBadInput;
  const auto case_settings = caseSettingsOrReport(
      *valve_case, options.case_dir, SettingsUse::kClose, "compare", options.settings_overrides);
  if (!case_settings) return kExitBadInput;
  const SimulationSettings& settings = *case_settings;

  // One tissue per cord file ("-" or none: the case's own).
  std::vector<std::string> tissues(options.cords_files.size(), "-");
  if (!options.tissues.empty()) {
    tissues = splitLabels(options.tissues);
    if (tissues.size() != options.cords_files.size()) {
      std::cerr << "error: compare: --tissues: " << tissues.size() << " file(s) for "
                << options.cords_files.size() << " cord file(s); give one per cord file ('-' "
                << "for the case's own tissue)\n";
      return kExitBadInput;
    }
  }

  // Read every cord and tissue file first: a typo in the last one must not cost the earlier
  // closures.
  std::vector<ComparedSet> sets;
  for (std::size_t i = 0; i < options.cords_files.size(); ++i) {
    const auto cords = resolveCords(*valve_case, options.cords_files[i]);
    if (!cords) return kExitBadInput;
    ComparedSet set{labels[i], options.cords_files[i], *cords, *valve_case, {}, false, 0, {}, {}};
    if (tissues[i] == "-")
      printLinesToStderr(
          tissueBesideCordsNote("compare", options.cords_files[i], "--tissues, one per cord file"));
    if (tissues[i] != "-") {
      // Named with the option: in a list beside the cord files, a bare name could be either.
      Diagnostics diagnostics;
      if (!loadTissueFile(tissues[i], "compare: --tissues: " + tissues[i], set.valve_case,
                          diagnostics))
        return reportProblems(diagnostics);
      if (!tissueStepCapOrReport(set.valve_case, settings, "compare: --tissues: " + tissues[i]))
        return kExitBadInput;
    }
    sets.push_back(std::move(set));
  }

  // A synthetic case (make-case) carries its truth: say how far each set is from it.
  const std::optional<CaseTruth> truth = readCaseTruth(options.case_dir);
  if (truth) {
    for (ComparedSet& s : sets) s.recovery = recoveryAgainstTruth(s.cords, *truth);
  }

  if (const int failed = closeSets(*valve_case, settings, options, sets); failed != kExitOk)
    return failed;

  if (!options.settings_overrides.empty()) {
    std::cout << "simulator settings over the case's (--set):";
    for (const std::string& item : options.settings_overrides) std::cout << " " << item;
    std::cout << "\n";
  }
  std::cout << table1Header("Cord set");
  for (const ComparedSet& s : sets) std::cout << table1Row(s.label, s.metrics);
  if (valve_case->tracings.empty()) {
    std::cout << "(the case has no tracings: no deviation and no prolapse comparison)\n";
  } else {
    std::cout << "prolapse (tracings): "
              << joinSegments(sets.front().metrics.tracing_prolapse.segments) << "\n"
              << noiseFloorLine(truth);
  }
  for (const ComparedSet& s : sets) {
    std::cout << s.label << (s.converged ? "" : "  [closure NOT converged]") << ":\n"
              << closedValveSummary(s.metrics, "  ");
    if (s.recovery)
      std::cout << "  against the truth (truth/truth.json), median |rest / true - 1|: "
                << recoveryText(*s.recovery) << "\n";
  }
  if (!options.out_dir.empty()) {
    StagedOutput staged(options.out_dir, compareOutputFiles(options),
                        enfaceFiguresBeyond(options.out_dir, sets.size()), "compare");
    const std::filesystem::path& out = staged.dir();
    writeFileAtomically(out / "compare.md",
                        compareMarkdown(*valve_case, sets, options.settings_overrides, truth));
    writeFileAtomically(out / "compare.csv", compareCsv(sets));
    writeFileAtomically(out / "cords.csv", cordsCsv(*valve_case, sets, truth));
    const std::string sections = sectionsSvg(*valve_case, sets);
    if (!sections.empty()) writeFileAtomically(out / "sections.svg", sections);
    // One atrial view per set, numbered in the order given (labels need not be file names),
    // all on one height scale and at one size: a shade means the same height in every file.
    std::vector<EnfaceClosure> closures;
    for (const ComparedSet& set : sets)
      closures.push_back({set.closed_V, valve_case->name + ", " + set.label, set.metrics});
    const std::vector<std::string> enface = enfaceFiguresSvg(*valve_case, closures);
    for (std::size_t i = 0; i < sets.size(); ++i)
      writeFileAtomically(out / enfaceFigureName(i + 1), enface[i]);
    std::cout << wroteLine(options.out_dir, staged.publish())
              << " (enface_K.svg: the K-th cord set given)\n";
  }
  return kExitOk;
}

std::vector<std::string> compareOutputFiles(const CompareOptions& options) {
  std::vector<std::string> files = {"compare.md", "compare.csv", "cords.csv", "sections.svg"};
  for (std::size_t k = 1; k <= options.cords_files.size(); ++k)
    files.push_back(enfaceFigureName(k));
  return files;
}

}  // namespace chordfit::cli
