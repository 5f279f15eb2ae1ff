// chordfit: command-line entry. The only translation unit that includes CLI11 (slow headers);
// it fills the option structs of commands.h and dispatches.
#include <exception>
#include <iostream>

#include <CLI/CLI.hpp>

#include "tools/commands.h"

namespace {

using namespace chordfit::cli;

void addValidate(CLI::App& app, ValidateOptions& o) {
  CLI::App* cmd = app.add_subcommand("validate", "Check a case directory and print its summary");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory (holds case.json)")->required();
}

void addMakeValve(CLI::App& app, MakeValveOptions& o) {
  CLI::App* cmd =
      app.add_subcommand("make-valve", "Write a parametric mitral valve case (open state)");
  cmd->add_option("--out", o.out_dir, "Output case directory")->required();
  cmd->add_option("--edge", o.edge_mm, "Target edge length, mm")->capture_default_str();
  cmd->add_option("--annulus", o.annulus_file,
                  "Annulus polyline (plain JSON point list or Slicer .mrk.json) to use instead "
                  "of the parametric saddle; frame: anterior at +x, atrium at +z");
  cmd->add_option("--name", o.name, "Case name")->capture_default_str();
}

void addHeuristic(CLI::App& app, HeuristicCommandOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "heuristic", "Build the paper's heuristic cord set (automatic cord placement if needed)");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory")->required();
  cmd->add_option("--out", o.out_file, "Output CordSet JSON")->required();
  cmd->add_option("--primary-spacing", o.primary_spacing_mm,
                  "Arc length between primary cords on the free edge, mm")
      ->capture_default_str();
  cmd->add_option("--secondary-spacing", o.secondary_spacing_mm,
                  "Spacing of secondary cords on the belly, mm")
      ->capture_default_str();
  cmd->add_option("--secondary-depth", o.secondary_depth_mm,
                  "Distance of secondary cords from the free edge, mm")
      ->capture_default_str();
}

void addMetrics(CLI::App& app, MetricsOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "metrics", "Deviation to the tracings, area and prolapse of a closed mesh (Table 1 row)");
  cmd->add_option("CASE_DIR", o.case_dir, "Case directory")->required();
  cmd->add_option("--mesh", o.mesh_file, "Closed mesh (same topology as the case mesh)")
      ->required();
  cmd->add_option("--out", o.out_file, "Write metrics JSON here");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"chordfit: chordae tendineae fitting for mitral valve closure simulation"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "chordfit 0.1.0");
  ValidateOptions validate;
  MakeValveOptions make_valve;
  HeuristicCommandOptions heuristic;
  MetricsOptions metrics;
  addValidate(app, validate);
  addMakeValve(app, make_valve);
  addHeuristic(app, heuristic);
  addMetrics(app, metrics);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  }
  try {
    if (app.got_subcommand("validate")) return runValidate(validate);
    if (app.got_subcommand("make-valve")) return runMakeValve(make_valve);
    if (app.got_subcommand("heuristic")) return runHeuristic(heuristic);
    if (app.got_subcommand("metrics")) return runMetrics(metrics);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitFailure;
  }
  return kExitBadInput;
}
