// chordfit fit: fit the cord rest lengths (and optionally the PM tips) of a case to its
// tracings (issue 5). Thin: parse and check the options, call inverse::fitCords, write the
// outputs. The closed mesh and its metrics are written by the simulate command's code path
// (runSimulate on the fitted cords: a full closure from the open state, the same files and
// scalars as `chordfit simulate`), then metrics.json is extended with the fit's keys.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/case_io.h"
#include "core/cordset_io.h"
#include "core/metrics.h"
#include "core/section_figure.h"
#include "core/simulator.h"
#include "core/svg_line_plot.h"
#include "inverse/fit_cords.h"
#include "tools/command_support.h"
#include "tools/commands.h"

namespace chordfit::cli {

namespace {

using inverse::IterationRecord;

constexpr const char* kSeedColour = "#9a9a9a";  // the seed closure in sections.svg

std::string joinNames(const std::vector<std::string>& names) {
  std::string joined;
  for (const std::string& n : names) joined += (joined.empty() ? "" : "|") + n;
  return joined;
}

std::string formatFixed(double value, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

std::string formatWeight(double weight) {
  std::ostringstream text;
  text << weight;
  return text.str();
}

std::string convergenceCsv(const std::vector<IterationRecord>& history) {
  std::ostringstream csv;
  csv.precision(10);
  csv << "stage,iteration,cost,best_cost,mean_deviation_mm,forward_sims,elapsed_s\n";
  for (const IterationRecord& r : history) {
    csv << r.stage << "," << r.iteration << "," << r.cost << "," << r.best_cost << ","
        << r.mean_deviation_mm << "," << r.forward_sims << "," << r.elapsed_s << "\n";
  }
  return csv.str();
}

std::string convergenceSvg(const std::vector<IterationRecord>& history, const std::string& name) {
  PlotSeries cost{"cost at the current point", {}, {}, true, true};
  PlotSeries best{"best cost", {}, {}, false, true};
  PlotSeries mean{"mean deviation (AvgD)", {}, {}, true, true};
  for (const IterationRecord& r : history) {
    cost.x.push_back(r.forward_sims), cost.y.push_back(r.cost);
    best.x.push_back(r.forward_sims), best.y.push_back(r.best_cost);
    mean.x.push_back(r.forward_sims), mean.y.push_back(r.mean_deviation_mm);
  }
  const std::vector<PlotPanel> panels = {
      {"Fit cost (" + name + ")", "forward simulations", "cost", {cost, best}, true},
      {"Mean deviation to the tracings",
       "forward simulations",
       "mean deviation (mm)",
       {mean},
       false}};
  return svgLinePlots(panels, 1, 720, 320);
}

// A cord's rest-length SD (% of the fitted length) and data sensitivity (mm of residual
// movement, root sum of squares, per 1 % of its length) from its parameter; empty strings
// when unknown (locked cord, no uncertainty).
struct CordUncertaintyText {
  std::string sd = "–", sensitivity = "–";
};

CordUncertaintyText cordUncertainty(const inverse::FitOutcome& fit, std::size_t cord) {
  CordUncertaintyText text;
  const int p = cord < fit.cord_parameter.size() ? fit.cord_parameter[cord] : -1;
  if (p < 0 || !fit.uncertainty.ok() || fit.x(p) <= 0.0) return text;
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.1f%s", 100.0 * fit.uncertainty.sd(p) / fit.x(p),
                fit.uncertainty.at_bound[p] ? " (at bound)" : "");
  text.sd = buffer;
  std::snprintf(buffer, sizeof buffer, "%.3f", 0.01 * fit.x(p) * fit.uncertainty.sensitivity(p));
  text.sensitivity = buffer;
  return text;
}

std::string cordTable(const ValveCase& c, const inverse::FitOutcome& fit) {
  const std::vector<std::string> groups = inverse::cordGroups(c, fit.seed);
  const Eigen::VectorXd spans = closedSpans(fit.fitted, fit.final_evaluation.closed_V);
  std::ostringstream md;
  md << "| Cord | Group | Kind | Seed length (mm) | Fitted length (mm) | Scale | Closed span (mm) "
        "| "
        "± SD (%) | Sensitivity (mm per 1 %) | Provenance | Locked |\n"
        "|---:|---|---|---:|---:|---:|---:|---:|---:|---|---|\n";
  char line[360];
  for (std::size_t i = 0; i < fit.fitted.cords.size(); ++i) {
    const Cord& s = fit.seed.cords[i];
    const Cord& f = fit.fitted.cords[i];
    const CordUncertaintyText u = cordUncertainty(fit, i);
    const double span = spans(static_cast<Eigen::Index>(i));
    std::snprintf(line, sizeof line,
                  "| %zu | %s | %s | %.3f | %.3f | %.4f | %.3f%s | %s | %s | %s | %s |\n", i,
                  groups[i].c_str(), toString(f.kind), s.rest_length, f.rest_length, f.scale(),
                  span, span < f.rest_length - kSlackMarginMm ? " (slack)" : "", u.sd.c_str(),
                  u.sensitivity.c_str(), toString(f.provenance), f.locked ? "yes" : "no");
    md << line;
  }
  return md.str();
}

int slackCords(const inverse::FitOutcome& fit) {
  const Eigen::VectorXd spans = closedSpans(fit.fitted, fit.final_evaluation.closed_V);
  int count = 0;
  for (std::size_t i = 0; i < fit.fitted.cords.size(); ++i)
    count += spans(static_cast<Eigen::Index>(i)) < fit.fitted.cords[i].rest_length - kSlackMarginMm;
  return count;
}

// Cords whose fitted length the tracings pin down: rest-length SD below 3 % (the issue's
// recovery tolerance) and not at a bound.
int identifiedCords(const inverse::FitOutcome& fit) {
  int count = 0;
  for (std::size_t c = 0; c < fit.cord_parameter.size(); ++c) {
    const int p = fit.cord_parameter[c];
    if (p < 0 || !fit.uncertainty.ok() || fit.uncertainty.at_bound[p]) continue;
    if (fit.uncertainty.sd(p) < 0.03 * fit.x(p)) ++count;
  }
  return count;
}

int freeCords(const inverse::FitOutcome& fit) {
  int count = 0;
  for (int p : fit.cord_parameter) count += p >= 0 ? 1 : 0;
  return count;
}

// uncertainty.csv: one row per parameter.
std::string uncertaintyCsv(const inverse::FitOutcome& fit) {
  std::ostringstream csv;
  csv.precision(10);
  csv << "parameter,name,kind,value,sd,relative_sd_percent,sensitivity_mm_per_unit,at_bound\n";
  for (Eigen::Index p = 0; p < fit.x.size(); ++p) {
    const bool scale = fit.parameter_is_scale[p];
    csv << p << ",\"" << fit.parameter_names[p] << "\"," << (scale ? "scale" : "tip_offset_mm")
        << "," << fit.x(p) << "," << fit.uncertainty.sd(p) << ",";
    if (scale && fit.x(p) > 0.0) csv << 100.0 * fit.uncertainty.sd(p) / fit.x(p);
    csv << "," << fit.uncertainty.sensitivity(p) << ","
        << (fit.uncertainty.at_bound[p] ? "yes" : "no") << "\n";
  }
  return csv.str();
}

std::string report(const ValveCase& c, const FitCommandOptions& o, const inverse::FitOutcome& fit,
                   const ValveMetrics& seed_metrics, const ValveMetrics& fit_metrics) {
  std::ostringstream md;
  md << "# Cord fit: " << c.name << "\n\n";
  md << "- parameters: " << o.params << " (" << fit.x.size() << "), optimizer: " << o.optimizer
     << ", scale bounds [" << o.scale_bounds[0] << ", " << o.scale_bounds[1] << "]\n";
  md << "- data residual: "
     << (o.distance == "own-leaflet" ? "each tracing point to its own leaflet's closed surface"
                                     : "each tracing point to the whole closed mesh")
     << " (--distance " << o.distance << "); AvgD below is always to the whole mesh\n";
  md << "- section residuals: "
     << (o.section_weight > 0.0 ? "weight " + formatWeight(o.section_weight) +
                                      " (closed-mesh sections straying more than 1.5 mm from "
                                      "their plane's tracings are charged)"
                                : std::string("off"))
     << "\n";
  md << "- global pre-fit factor: " << fit.prefit_factor << (o.prefit ? "" : " (disabled)")
     << "; per kind: primaries " << fit.prefit_primary_factor << ", secondaries "
     << fit.prefit_secondary_factor << "\n";
  md << "- segment pre-fit: "
     << (fit.segment_prefit_changes.empty() ? std::string("no change")
                                            : joinSegments(fit.segment_prefit_changes))
     << "\n";
  if (o.tissue_prefit) {
    md << "- tissue pre-fit (stiffness factor per segment): "
       << (fit.tissue_prefit_changes.empty() ? std::string("no change (uniform tissue kept)")
                                             : joinSegments(fit.tissue_prefit_changes) +
                                                   "; the cords were fitted on this "
                                                   "tissue (tissue.json)")
       << "\n";
  }
  md << "- forward simulations: " << fit.forward_sims << ", fit time: " << fit.seconds
     << " s, threads: " << o.threads << "\n";
  md << "- termination: " << fit.termination << "\n";
  md << "- cost: seed " << fit.seed_evaluation.cost << ", fit " << fit.final_evaluation.cost
     << "\n\n";
  md << "## Table 1: seed vs fit\n\n"
     << table1Header() << table1Row("seed", seed_metrics) << table1Row("fit", fit_metrics) << "\n";
  md << "Prolapse segments: tracings " << joinSegments(fit_metrics.tracing_prolapse.segments)
     << "; in the tracing planes: seed " << joinSegments(seed_metrics.section_prolapse.segments)
     << ", fit " << joinSegments(fit_metrics.section_prolapse.segments)
     << " (Table 1 compares these); tissue: seed "
     << joinSegments(seed_metrics.mesh_prolapse.segments) << ", fit "
     << joinSegments(fit_metrics.mesh_prolapse.segments) << "\n\n";
  md << "![Seed (dashed) and fitted closures against the tracings, one panel per image plane]"
        "(sections.svg)\n\n";
  md << "## Cords\n\nScale = fitted length / the cord's seed_rest_length (heuristic). ± SD: the "
        "fitted length's standard deviation from the Jacobian at the fit "
        "(inverse/fit_uncertainty.h; residual SD "
     << (fit.uncertainty.ok()
             ? formatFixed(fit.uncertainty.sigma_mm, 2) + " mm, correlated over " +
                   formatFixed(fit.uncertainty.correlation_time, 1) + " tracing points"
             : std::string("not computed: ") +
                   (fit.uncertainty.error.empty() ? "--no-uncertainty" : fit.uncertainty.error))
     << "); sensitivity: how far the data residuals move (root sum of squares) per 1 % of the "
        "cord's length. Closed span: the cord's tip-to-vertex distance in the fitted closure; a "
        "slack cord (span below its length) pulls on nothing there, so any length down to its "
        "span closes the valve the same way: the tracings bound it from below only. "
     << slackCords(fit) << " of " << fit.fitted.cords.size() << " cords are slack. "
     << identifiedCords(fit) << " of " << freeCords(fit)
     << " free cords are determined to better than 3 %.\n\n"
     << cordTable(c, fit);
  return md.str();
}

}  // namespace

int runFit(const FitCommandOptions& o) {
  const auto mode = inverse::parseParameterMode(o.params);
  if (!mode) {
    std::cerr << "error: fit: --params: expected scales, groups or scales+tips, got \"" << o.params
              << "\"\n";
    return kExitBadInput;
  }
  if (!inverse::makeOptimizer(o.optimizer)) {
    std::cerr << "error: fit: --optimizer: expected " << joinNames(inverse::optimizerNames())
              << ", got \"" << o.optimizer << "\"\n";
    return kExitBadInput;
  }
  if (o.distance != "own-leaflet" && o.distance != "surface") {
    std::cerr << "error: fit: --distance: expected own-leaflet or surface, got \"" << o.distance
              << "\"\n";
    return kExitBadInput;
  }
  if (o.scale_bounds.size() != 2 || !(o.scale_bounds[0] > 0.0) ||
      !(o.scale_bounds[0] < o.scale_bounds[1])) {
    std::cerr << "error: fit: --scale-bounds: need two numbers 0 < lower < upper\n";
    return kExitBadInput;
  }
  if (!(o.section_weight >= 0.0) || !std::isfinite(o.section_weight)) {
    std::cerr << "error: fit: --section-weight: must be a finite number >= 0, got "
              << o.section_weight << "\n";
    return kExitBadInput;
  }
  if (o.max_sims < 1 || o.threads < 1 || !(o.tip_box_mm > 0.0) || !(o.fd_scale_step > 0.0) ||
      !(o.fd_tip_step_mm > 0.0)) {
    std::cerr << "error: fit: --max-sims, --threads, --tip-box and the finite-difference steps "
                 "must be positive\n";
    return kExitBadInput;
  }
  const auto valve_case = loadCaseOrReport(o.case_dir);
  if (!valve_case) return kExitBadInput;
  if (valve_case->tracings.empty()) {
    std::cerr << "error: " << o.case_dir << ": case.json: tracings: the fit needs tracings\n";
    return kExitBadInput;
  }
  const auto seed = resolveCords(*valve_case, o.seed_cords_file);
  if (!seed) return kExitBadInput;
  const auto case_settings = caseSettingsOrReport(*valve_case, o.case_dir);
  if (!case_settings) return kExitBadInput;
  const SimulationSettings& settings = *case_settings;

  inverse::FitOptions options;
  options.mode = *mode;
  options.bounds.scale_lower = o.scale_bounds[0];
  options.bounds.scale_upper = o.scale_bounds[1];
  options.bounds.tip_box_mm = o.tip_box_mm;
  options.prefit.enabled = o.prefit;
  options.segment_prefit.enabled = o.prefit;
  options.tissue_prefit.enabled = o.tissue_prefit;
  options.optimizer = o.optimizer;
  options.max_sims = o.max_sims;
  options.finite_difference.threads = o.threads;
  options.finite_difference.scale_step = o.fd_scale_step;
  options.finite_difference.tip_step_mm = o.fd_tip_step_mm;
  options.finite_difference.warm_start = o.fd_warm_start;
  options.residual.own_leaflet = o.distance == "own-leaflet";
  options.residual.section_weight = o.section_weight;
  options.uncertainty = o.uncertainty;
  if (!o.quiet) {
    std::printf("fitting %s: %zu cords, %s, %s, at most %d forward runs, %d threads\n",
                valve_case->name.c_str(), seed->cords.size(), o.params.c_str(), o.optimizer.c_str(),
                o.max_sims, o.threads);
    options.on_iteration = [](const IterationRecord& r) {
      std::printf("%-7s iter %4d  cost %10.4f  best %10.4f  mean %7.4f mm  sims %4d  %7.1f s\n",
                  r.stage.c_str(), r.iteration, r.cost, r.best_cost, r.mean_deviation_mm,
                  r.forward_sims, r.elapsed_s);
      std::fflush(stdout);
    };
  }
  const inverse::FitOutcome fit = inverse::fitCords(*valve_case, *seed, settings, options);
  if (!fit.ok()) {
    std::cerr << "error: " << o.case_dir << ": " << fit.error << "\n";
    return kExitSimulationFailed;
  }

  const std::filesystem::path out(o.out_dir);
  writeCordSet(out / "cords.json", fit.fitted, &valve_case->mesh);
  // The tissue the cords were fitted on, when the tissue pre-fit changed it; the closure
  // written below uses it too.
  if (fit.tissue.size() > 0) writeTissueFile(out / "tissue.json", fit.tissue);
  // closed.ply, closed.vtk and metrics.json exactly as `chordfit simulate` writes them.
  SimulateOptions simulate;
  simulate.case_dir = o.case_dir;
  simulate.cords_file = (out / "cords.json").string();
  if (fit.tissue.size() > 0) simulate.tissue_file = (out / "tissue.json").string();
  simulate.out_dir = o.out_dir;
  simulate.quiet = true;
  std::printf("fitted cords: full closure from the open state\n");
  const int simulated = runSimulate(simulate);
  if (simulated != kExitOk) return simulated;

  const ValveMetrics seed_metrics = computeMetrics(*valve_case, fit.seed_evaluation.closed_V);
  const ValveMetrics fit_metrics = computeMetrics(*valve_case, fit.final_evaluation.closed_V);
  std::string metrics_text;
  readWholeFile(out / "metrics.json", metrics_text);
  nlohmann::json metrics = nlohmann::json::parse(metrics_text);
  metrics["optimizer"] = o.optimizer;
  metrics["params"] = o.params;
  metrics["parameters"] = fit.x.size();
  metrics["forward_sims"] = fit.forward_sims + 1;  // + the closure just written
  metrics["unsettled_sims"] = fit.unsettled_sims;  // of the fit's runs (not the one written)
  metrics["fit_seconds"] = fit.seconds;
  metrics["initial_mean_mm"] = fit.seed_evaluation.mean_deviation_mm;
  metrics["initial_cost"] = fit.seed_evaluation.cost;
  metrics["final_cost"] = fit.final_evaluation.cost;
  metrics["prefit_factor"] = fit.prefit_factor;
  metrics["prefit_primary_factor"] = fit.prefit_primary_factor;
  metrics["prefit_secondary_factor"] = fit.prefit_secondary_factor;
  metrics["segment_prefit"] = fit.segment_prefit_changes;
  metrics["tissue_prefit"] = fit.tissue_prefit_changes;
  metrics["distance"] = o.distance;  // the data residual the fit minimised
  metrics["section_weight"] = o.section_weight;
  metrics["scale_bounds"] = o.scale_bounds;
  if (o.uncertainty) {
    nlohmann::json u = {{"jacobian_sims", fit.uncertainty.jacobian_sims},
                        {"seconds", fit.uncertainty_seconds}};
    if (fit.uncertainty.ok()) {
      u["residual_sd_mm"] = fit.uncertainty.sigma_mm;
      u["correlation_time"] = fit.uncertainty.correlation_time;
      u["identified_cords"] = identifiedCords(fit);
      u["free_cords"] = freeCords(fit);
    } else {
      u["error"] = fit.uncertainty.error;
    }
    metrics["uncertainty"] = u;
  }
  metrics["slack_cords"] = slackCords(fit);
  metrics["termination"] = fit.termination;
  metrics["threads"] = o.threads;
  writeFileAtomically(out / "metrics.json", metrics.dump(2) + "\n");
  writeFileAtomically(out / "convergence.csv", convergenceCsv(fit.history));
  if (fit.uncertainty.ok()) writeFileAtomically(out / "uncertainty.csv", uncertaintyCsv(fit));
  writeFileAtomically(out / "convergence.svg", convergenceSvg(fit.history, o.optimizer));
  writeFileAtomically(out / "report.md", report(*valve_case, o, fit, seed_metrics, fit_metrics));
  // Replaces simulate's figure of the fitted closure alone: the seed closure beside it.
  writeFileAtomically(
      out / "sections.svg",
      caseSectionFigureSvg(*valve_case,
                           {{"seed closure", fit.seed_evaluation.closed_V, kSeedColour, true, 1.4},
                            {"fitted closure", fit.final_evaluation.closed_V, "", false, 2.0}},
                           {valve_case->name + ": seed and fitted closures against the tracings (" +
                            o.optimizer + ", " + o.params + ")"}));

  std::printf("fit: %s after %d forward runs, %.1f s (%s)\n", o.optimizer.c_str(), fit.forward_sims,
              fit.seconds, fit.termination.c_str());
  if (fit.unsettled_sims > 0) {
    std::printf(
        "note: %d of the %d forward runs reached the step cap without settling (their state is "
        "the mean over the last steps; docs/performance.md)\n",
        fit.unsettled_sims, fit.forward_sims);
  }
  if (fit.uncertainty.ok()) {
    std::printf(
        "uncertainty: %d of %d free cords determined to better than 3 %% (residual SD %.2f mm, "
        "correlated over %.1f points; %d extra closures, %.1f s; report.md, uncertainty.csv)\n",
        identifiedCords(fit), freeCords(fit), fit.uncertainty.sigma_mm,
        fit.uncertainty.correlation_time, fit.uncertainty.jacobian_sims, fit.uncertainty_seconds);
  } else if (o.uncertainty && !fit.uncertainty.error.empty()) {
    std::printf("note: %s\n", fit.uncertainty.error.c_str());
  }
  std::cout << table1Header() << table1Row("seed", seed_metrics) << table1Row("fit", fit_metrics);
  std::cout << "wrote " << (out / "cords.json").string()
            << ", closed.ply, closed.vtk, metrics.json, convergence.csv, convergence.svg, "
               "sections.svg, "
            << (fit.uncertainty.ok() ? "uncertainty.csv, " : "") << "report.md\n";
  return kExitOk;
}

}  // namespace chordfit::cli
