#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/case_io.h"
#include "core/curve_io.h"
#include "core/parametric_valve.h"
#include "tools/command_support.h"
#include "tools/commands.h"
#include "tools/staged_output.h"

namespace chordfit::cli {

namespace {

// The anatomy options and the ValveParameters fields they set. closed_saddle_height_mm comes
// before saddle_height_mm, which it contains, and posterior_side_height_mm before
// posterior_height_mm likewise, for the replacements of optionMessage.
struct AnatomyOption {
  const char* field;
  const char* option;
  double ValveParameters::*member;
};
constexpr AnatomyOption kAnatomyOptions[] = {
    {"target_edge_mm", "--edge", &ValveParameters::target_edge_mm},
    {"ap_diameter_mm", "--ap", &ValveParameters::ap_diameter_mm},
    {"cc_diameter_mm", "--cc", &ValveParameters::cc_diameter_mm},
    {"closed_saddle_height_mm", "--closed-saddle", &ValveParameters::closed_saddle_height_mm},
    {"saddle_height_mm", "--saddle", &ValveParameters::saddle_height_mm},
    {"anterior_height_mm", "--anterior-height", &ValveParameters::anterior_height_mm},
    {"posterior_side_height_mm", "--posterior-side-height",
     &ValveParameters::posterior_side_height_mm},
    {"posterior_height_mm", "--posterior-height", &ValveParameters::posterior_height_mm},
    {"commissural_height_mm", "--commissural-height", &ValveParameters::commissural_height_mm},
    {"indentation_depth", "--indentation", &ValveParameters::indentation_depth}};

// makeParametricValve's message with the fields options set named as the options:
// "<field> must be ..." as "<option>: must be ..." (with the other fields it names, a bound
// derived from them, as options too), and a field named inside another message as its option.
std::string optionMessage(const std::string& message) {
  std::string text = message;
  for (const AnatomyOption& o : kAnatomyOptions) {
    const std::string prefix = std::string(o.field) + " ";
    if (message.rfind(prefix, 0) == 0) text = o.option + (": " + message.substr(prefix.size()));
  }
  for (const AnatomyOption& o : kAnatomyOptions) {
    for (std::size_t at = text.find(o.field); at != std::string::npos; at = text.find(o.field))
      text.replace(at, std::string(o.field).size(), o.option);
  }
  return text;
}

// The anatomy options given other than their defaults ("--anterior-height 1e-300"), for a
// message about the valve they make together.
std::string changedOptions(const ValveParameters& p, const std::string& annulus_file) {
  const ValveParameters defaults;
  std::string text = annulus_file.empty() ? "" : "--annulus " + annulus_file;
  for (const AnatomyOption& o : kAnatomyOptions) {
    if (p.*o.member == defaults.*o.member) continue;
    char value[32];
    std::snprintf(value, sizeof value, "%g", p.*o.member);
    text += (text.empty() ? "" : ", ") + std::string(o.option) + " " + value;
  }
  return text.empty() ? "the defaults" : text;
}

// --ap and --cc shape the parametric annulus only: the file's points replace it (the valve
// was made from the file without a word about them).
void noteDiametersIgnored(const MakeValveOptions& options) {
  std::string ignored;
  for (const char* option : {"--ap", "--cc"})
    if (optionGiven(options.given_options, option))
      ignored += (ignored.empty() ? "" : " and ") + std::string(option);
  if (!ignored.empty())
    printNote("make-valve: %s do%s not act with --annulus: the annulus file gives the diameters\n",
              ignored.c_str(), ignored.size() > 4 ? "" : "es");
}

}  // namespace

int runMakeValve(const MakeValveOptions& options) {
  // The check loadCase makes of case.json's name: without it the case written was one that
  // validate refused (a newline), or one with an empty Case cell in tables ("").
  if (const std::string problem = caseNameProblem(options.name); !problem.empty()) {
    std::cerr << "error: make-valve: --name: " << problem << "\n";
    return kExitBadInput;
  }
  ValveParameters parameters = options.parameters;
  if (!options.annulus_file.empty()) {
    Diagnostics diagnostics;
    Curve curve;
    if (!readCurve(options.annulus_file, curve, diagnostics, options.annulus_file)) {
      return reportProblems(diagnostics);
    }
    parameters.annulus_polyline = curve.points;
    noteDiametersIgnored(options);
  }
  ParametricValve valve;
  try {
    valve = makeParametricValve(parameters);
  } catch (const std::invalid_argument& e) {
    const std::string by_option = optionMessage(e.what());
    const std::string polyline = "annulus_polyline ";
    if (!options.annulus_file.empty() && by_option.rfind(polyline, 0) == 0) {
      // The file's own field: its points are the polyline.
      std::cerr << "error: " << options.annulus_file << ": points: the annulus "
                << by_option.substr(polyline.size()) << "\n";
    } else if (by_option != e.what()) {
      std::cerr << "error: make-valve: " << by_option << "\n";
    } else {
      std::cerr << "error: " << (options.annulus_file.empty() ? "make-valve" : options.annulus_file)
                << ": parameters: " << e.what() << "\n";
    }
    return kExitBadInput;
  }
  valve.valve_case.name = options.name;
  // Accepted but unlike an adult mitral valve: say so, the valve is made as asked.
  const ValveParameters& p = parameters;
  if (p.commissural_height_mm >= p.anterior_height_mm)
    printNote(
        "make-valve: the commissures (%g mm, --commissural-height) are as tall as "
        "the anterior leaflet (%g mm) or taller: an unusual valve (defaults 8 and 23 "
        "mm)\n",
        p.commissural_height_mm, p.anterior_height_mm);
  if (options.annulus_file.empty() &&
      (p.ap_diameter_mm / p.cc_diameter_mm < 0.6 || p.ap_diameter_mm / p.cc_diameter_mm > 1.1))
    printNote(
        "make-valve: --ap / --cc = %.2f; an adult mitral annulus is wider than "
        "deep (about 0.8, the defaults 28 / 35 mm)\n",
        p.ap_diameter_mm / p.cc_diameter_mm);
  fitStepCapToMesh(valve.valve_case);
  // An earlier case there (make-valve's, import-mesh's, make-case's) has files this one does
  // not, its tracings, cords, truth: they go, so that none describes another valve beside it.
  const std::vector<std::string> files = makeValveOutputFiles();
  StagedOutput staged(options.out_dir, files, caseDirectoryFilesBesides(files), kCaseWriter);
  writeCase(staged.dir(), valve.valve_case);
  // Read back with every check of validate: parameters within their ranges can still make
  // a mesh validate refuses (--anterior-height 1e-300 gave zero-area triangles), and a
  // case written is a case the other commands take.
  Diagnostics check;
  if (!loadCase(staged.dir(), check)) {
    std::cerr << "error: make-valve: the case these options make (" +
                     changedOptions(parameters, options.annulus_file) +
                     ") would not validate, so it was not written (a value too small or too "
                     "large for the others?):\n";
    check.print(std::cerr);
    return kExitBadInput;
  }
  const StagedOutput::Published published = staged.publish();
  std::cout << wroteLine(options.out_dir, published) << "\n" << caseSummary(valve.valve_case);
  return kExitOk;
}

std::vector<std::string> makeValveOutputFiles() { return caseFileNames(); }

}  // namespace chordfit::cli
