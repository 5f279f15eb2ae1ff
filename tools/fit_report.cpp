#include "tools/fit_report.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "core/cordset.h"
#include "core/counted.h"
#include "core/joined.h"
#include "core/svg_line_plot.h"
#include "tools/command_support.h"
#include "tools/shell_word.h"

namespace chordfit::cli {

namespace {

using inverse::IterationRecord;

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
  if (fit.uncertainty.sensitivity(p) == 0.0) {
    // No tracing point moves with it (a slack cord): its SD would be the prior's width alone,
    // hundreds of percent, read as a measurement.
    text.sd = "prior only";
    text.sensitivity = "0";
    return text;
  }
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
  const Eigen::VectorXd& spans = fit.closed_spans;
  std::ostringstream md;
  // Start: the --seed-cords set's length, where the fit began (a manual edit's); the scale is
  // always of the cord's seed rest length (seed_rest_length_mm, the heuristic's), as in the cord
  // file: Scale x Seed rest length = Fitted length. One column for both read "seed 23.084,
  // scale 0.8" for a manual cord whose seed rest length is 28.855.
  md << "| Cord | Group | Kind | Seed rest length (mm) | Start length (mm) | Fitted length (mm) | "
        "Scale (× seed rest length) | Closed span (mm) | ± SD (%) | Sensitivity (mm per 1 %) | "
        "Provenance | Locked |\n"
        "|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---|---|\n";
  char line[400];
  for (std::size_t i = 0; i < fit.fitted.cords.size(); ++i) {
    const Cord& s = fit.seed.cords[i];
    const Cord& f = fit.fitted.cords[i];
    CordUncertaintyText u = cordUncertainty(fit, i);
    const double span = spans(static_cast<Eigen::Index>(i));
    // A group factor's SD belongs to the group (--params groups): a cord of it that hangs
    // slack is not determined by it, however narrow the group's SD.
    const int p = fit.cord_parameter[i];
    const bool shared =
        p >= 0 && std::count(fit.cord_parameter.begin(), fit.cord_parameter.end(), p) > 1;
    const bool measured = u.sd != "–" && u.sd != "prior only";
    if (shared && measured && slackAtSpan(span, f.rest_length)) u.sd += " (group's; slack)";
    // The sensitivity too is the group factor's: all its cords move together.
    if (shared && measured) u.sensitivity += " (group's)";
    std::snprintf(line, sizeof line,
                  "| %zu | %s | %s | %.3f | %.3f | %.3f | %.4f | %.3f%s | %s | %s | %s | %s |\n", i,
                  groups[i].c_str(), toString(f.kind), f.seed_rest_length, s.rest_length,
                  f.rest_length, f.scale(), span,
                  slackAtSpan(span, f.rest_length) ? " (slack)" : "", u.sd.c_str(),
                  u.sensitivity.c_str(), toString(f.provenance), f.locked ? "yes" : "no");
    md << line;
  }
  return md.str();
}

// What the slack release did (inverse/slack_release.h), for report.md.
std::string slackReleaseLine(const inverse::FitOutcome& fit, bool enabled,
                             const std::string& params) {
  if (!enabled) return "off (--no-slack-release)";
  if (params == "groups")
    return "not run with --params groups (a group factor moves its slack and taut cords "
           "together)";
  const inverse::SlackReleaseOutcome& release = fit.slack_release;
  if (!release.ran) return "not run: --max-sims left no closure for it";
  const inverse::SlackReleaseProposal& p = release.proposal;
  auto reference = [&](double value) {
    // The reference leaves out the segments the segment pre-fit rescaled or the fit
    // prolapses (slack_release.h): taut cords there do not count.
    return value > 0.0 ? formatFixed(value, 3)
                       : std::string("none (no taut cord outside rescaled or prolapsing segments)");
  };
  const std::string typical = "typical scale: primaries " + reference(p.primary_reference) +
                              ", secondaries " + reference(p.secondary_reference);
  if (p.empty()) return "no slack cord below its kind's typical scale (" + typical + ")";
  std::string line =
      counted(p.cords.size(), "slack cord") + " raised to their kind's " + typical + "; ";
  const std::string costs = "data cost " + formatFixed(release.optimiser_data_cost, 3) + " -> " +
                            formatFixed(release.data_cost, 3);
  if (release.kept)
    line += "kept (" + costs + ")";
  else if (!release.error.empty())
    line += "not kept: its closure failed (" + release.error + ")";
  else
    line += "not kept: its closure fits worse (" + costs + ")";
  return line;
}

// The Carpentier segment of a cord's leaflet vertex ("P2"), "?" when it has none;
// `segment` is openStateSegments of the case mesh.
std::string cordSegment(const ValveCase& c, const Eigen::VectorXi& segment, const Cord& cord) {
  const int id = segment(cord.vertex);
  return id >= 0 ? segmentName(c.mesh.leaflet_names, id) : "?";
}

// A locked-cord trial's cords as "16" or "14, 16, 17".
std::string trialCords(const inverse::LockedCordTrial& trial, const std::string& separator = ", ") {
  std::string text;
  for (int cord : trial.cords) text += (text.empty() ? "" : separator) + std::to_string(cord);
  return text;
}

// The change of a trial's lengths: "+7.2" for one cord, "+3.1..+25.0" for several.
std::string trialChange(const inverse::FitOutcome& fit, const inverse::LockedCordTrial& trial) {
  double lo = 0.0, hi = 0.0;
  for (std::size_t k = 0; k < trial.cords.size(); ++k) {
    const double change =
        100.0 * (trial.lengths_mm[k] / fit.fitted.cords[trial.cords[k]].rest_length - 1.0);
    lo = k == 0 ? change : std::min(lo, change);
    hi = k == 0 ? change : std::max(hi, change);
  }
  char text[64];
  if (trial.cords.size() == 1 || hi - lo < 0.05)
    std::snprintf(text, sizeof text, "%+.1f", lo);
  else
    std::snprintf(text, sizeof text, "%+.1f..%+.1f", lo, hi);
  return text;
}

// "| predicted | data cost | AvgD |" cells of a trial.
std::string trialCells(const inverse::LockedCordTrial& trial) {
  if (!trial.error.empty()) return " " + trial.error + " | | |";
  return " " + formatFixed(100.0 * trial.predicted_drop, 1) + " | " +
         formatFixed(trial.data_cost, 3) + " | " + formatFixed(trial.mean_deviation_mm, 2) + " |";
}

// report.md's "Locked cords" section (inverse/locked_cord_probe.h), or "" when no cord is
// locked or the probe did not run.
std::string lockedCordSection(const ValveCase& c, const inverse::FitOutcome& fit) {
  const inverse::LockedCordProbes& probes = fit.locked_probes;
  if (probes.cords.empty()) return "";
  const std::vector<std::string> groups = inverse::cordGroups(c, fit.seed);
  const Eigen::VectorXi segment = openStateSegments(c.mesh);
  std::ostringstream md;
  md << "## Locked cords\n\n"
        "The fit keeps locked cords as they are. Each locked cord taut in the fitted closure "
        "was probed alone, the other cords as fitted (inverse/locked_cord_probe.h): two "
        "closures at ± "
     << formatWeight(100.0 * probes.relative_step)
     << " % of its length give the derivative of the data cost, the Gauss–Newton step on it "
        "gives a length (a change of at most ± "
     << formatWeight(100.0 * probes.max_change)
     << " %, within the scale bounds), and a full closure there measures it; then the taut "
        "locked cords of each segment that has two or more, together. A lower data cost there "
        "means the lock holds the fit back; to first order, re-fitting the free cords too could "
        "only lower it further. The predicted drop is the linear model's for the step as "
        "applied (capped and bounded). A slack locked cord pulls on nothing in the fitted closure "
        "and is not "
        "probed. Data cost of the fit: "
     << formatFixed(probes.fit_data_cost, 3) << ", AvgD "
     << formatFixed(probes.fit_mean_deviation_mm, 2) << " mm; "
     << counted(probes.forward_sims, "closure")
     << (probes.unsettled_sims > 0 ? " (" + std::to_string(probes.unsettled_sims) +
                                         " reached the step cap without settling)"
                                   : "")
     << ", " << formatFixed(probes.seconds, 1) << " s, outside --max-sims.\n\n";
  md << "| Cord | Group | Segment | Kind | Locked length (mm) | Closed span (mm) | Probe length "
        "(mm) | Change (%) | Predicted cost drop (%) | Data cost there | AvgD there (mm) |\n"
        "|---:|---|---|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const inverse::LockedCordProbe& p : probes.cords) {
    const Cord& cord = fit.fitted.cords[p.cord];
    md << "| " << p.cord << " | " << groups[p.cord] << " | " << cordSegment(c, segment, cord)
       << " | " << toString(cord.kind) << " | " << formatFixed(cord.rest_length, 3) << " | "
       << formatFixed(p.span_mm, 3);
    if (p.slack)
      md << " (slack) | – | – | – | – | – |\n";
    else if (p.trial.cords.empty())  // its difference closures failed
      md << " | – | – |" << trialCells(p.trial) << "\n";
    else
      md << " | " << formatFixed(p.trial.lengths_mm[0], 3) << " | " << trialChange(fit, p.trial)
         << " |" << trialCells(p.trial) << "\n";
  }
  if (!probes.segments.empty()) {
    md << "\nSegments, their taut locked cords together:\n\n"
          "| Segment | Cords | Change (%) | Predicted cost drop (%) | Data cost there | AvgD "
          "there (mm) |\n|---|---|---:|---:|---:|---:|\n";
    for (const inverse::LockedSegmentProbe& p : probes.segments)
      md << "| " << segmentName(c.mesh.leaflet_names, p.segment) << " | " << trialCords(p.trial)
         << " | " << trialChange(fit, p.trial) << " |" << trialCells(p.trial) << "\n";
  }
  md << "\n";
  return md.str();
}

}  // namespace

std::string tissuePrefitNotRun(const inverse::FitOutcome& fit, const FitCommandOptions& o) {
  if (!o.tissue_prefit || fit.tissue_prefit_ran) return "";
  if (fit.x.size() == 0) return "not run: no free cord";
  return "not run: --max-sims " + std::to_string(o.max_sims) + " leaves too few closures";
}

std::string tissueRetryLine(const inverse::FitOutcome& fit, const FitCommandOptions& o) {
  const inverse::TissueRetry& r = fit.tissue_retry;
  if (!o.tissue_retry) return "off (--no-tissue-retry)";
  if (fit.tissue_prefit_ran) return "not run: the tissue pre-fit ran (--tissue-prefit)";
  if (r.missing.empty()) return "not needed: the fit makes every prolapse the tracings show";
  std::string line = "the tracings show prolapse in " + joinSegments(r.missing) +
                     ", the fit did not (data cost " + formatFixed(r.data_cost_without, 3) +
                     ", AvgD " + formatFixed(r.mean_mm_without, 2) + " mm); ";
  if (!r.ran) return line + "not run: " + r.skipped;
  const std::string closures = std::to_string(r.forward_sims) + " closures";
  line += "softer tissue there (the tissue pre-fit): ";
  if (r.tissue_changes.empty())
    return line + "none fitted the tracings better, so the fit is the first (" + closures + ")";
  // Tissue changes are joined by "; ": one may itself hold a comma ("P3 0.3, cords 1.5").
  line += joined(r.tissue_changes, "; ") + ", then the fit again on it";
  if (!r.error.empty()) return line + " failed (" + r.error + "; " + closures + "); not kept";
  line += ": data cost " + formatFixed(r.data_cost_with, 3) + ", AvgD " +
          formatFixed(r.mean_mm_with, 2) + " mm, prolapse missed in " +
          joinSegments(r.missing_after) + " (" + closures + "); ";
  if (r.kept) return line + "kept (the cords were fitted on this tissue: tissue.json)";
  return line + "not kept (its data cost is not more than 1 % below the first's)";
}

nlohmann::json tissueRetryJson(const inverse::FitOutcome& fit) {
  const inverse::TissueRetry& r = fit.tissue_retry;
  nlohmann::json j = {{"missing_segments", r.missing}, {"ran", r.ran}, {"kept", r.kept}};
  if (!r.skipped.empty()) j["skipped"] = r.skipped;
  if (!r.missing.empty()) {
    j["data_cost_without"] = r.data_cost_without;
    j["mean_mm_without"] = r.mean_mm_without;
  }
  if (!r.ran) return j;
  j["forward_sims"] = r.forward_sims;
  j["tissue"] = r.tissue_changes;
  if (r.tissue_changes.empty()) return j;  // nothing softer fitted better: no second fit
  if (!r.error.empty()) {
    j["error"] = r.error;
  } else {
    j["data_cost_with"] = r.data_cost_with;
    j["mean_mm_with"] = r.mean_mm_with;
    j["missing_segments_after"] = r.missing_after;
  }
  return j;
}

void printLockedProbeSummary(const ValveCase& c, const FitCommandOptions& o,
                             const inverse::FitOutcome& fit) {
  const inverse::LockedCordProbes& probes = fit.locked_probes;
  if (probes.cords.empty()) return;
  const auto taut = std::count_if(probes.cords.begin(), probes.cords.end(),
                                  [](const inverse::LockedCordProbe& p) { return !p.slack; });
  const std::string count = std::to_string(probes.cords.size());
  if (taut == 0) {
    std::cout << "locked cords: " << count
              << ", all slack in the fitted closure (they hold nothing there)\n";
    return;
  }
  int failed = 0;
  auto countFailed = [&](const inverse::LockedCordTrial& t) { failed += t.error.empty() ? 0 : 1; };
  for (const inverse::LockedCordProbe& p : probes.cords) countFailed(p.trial);
  for (const inverse::LockedSegmentProbe& p : probes.segments) countFailed(p.trial);
  const std::string failures =
      failed > 0 ? "; " + std::to_string(failed) + " of its trials failed (report.md)" : "";
  const std::string closures = extraClosures(probes.forward_sims, probes.unsettled_sims);
  const inverse::LockedCordTrial* best = probes.best();
  const double drop =
      best && probes.fit_data_cost > 0.0 ? 1.0 - best->data_cost / probes.fit_data_cost : 0.0;
  if (drop < kLockedCordNoteDrop) {
    std::cout << "locked cords: " + count + ", " + std::to_string(taut) +
                     " taut; no one-step change of them (at most ±" +
                     formatWeight(100.0 * probes.max_change) + " %) lowers the data cost by " +
                     formatWeight(100.0 * kLockedCordNoteDrop) + " % or more (" + closures +
                     "; report.md, \"Locked cords\")" + failures + "\n";
    return;
  }
  const Eigen::VectorXi segment = openStateSegments(c.mesh);
  const bool one = best->cords.size() == 1;
  std::string what;
  if (one) {
    const Cord& cord = fit.fitted.cords[best->cords[0]];
    what = "cord " + std::to_string(best->cords[0]) + " (" + cordSegment(c, segment, cord) + " " +
           toString(cord.kind) + ") alone at " + formatFixed(best->lengths_mm[0], 2) + " mm";
  } else {
    what = cordSegment(c, segment, fit.fitted.cords[best->cords[0]]) + "'s cords " +
           trialCords(*best) + " together";
  }
  // edit-cords starts from the case's cords unless told the seed: keep the user's edits.
  const std::string seed =
      o.seed_cords_file.empty() ? "" : " --cords " + shellWord(o.seed_cords_file);
  printNote(
      "locked cords hold the fit back: %s\n",
      (what + " (" + trialChange(fit, *best) + " %): data cost -" + formatFixed(100.0 * drop, 0) +
       " %, AvgD " + formatFixed(probes.fit_mean_deviation_mm, 2) + " -> " +
       formatFixed(best->mean_deviation_mm, 2) + " mm; unlock (edit-cords " +
       shellWord(o.case_dir) + seed + " --unlock " + trialCords(*best, ",") +
       " --out FILE) to let the fit move " + (one ? "it" : "them") + " (" + closures +
       "; report.md, \"Locked cords\")" + failures)
          .c_str());
}

std::string worseThanSeedNote(const inverse::FitOutcome& fit) {
  if (!fit.seed_evaluation.ok() || !fit.final_evaluation.ok() ||
      fit.final_evaluation.cost <= fit.seed_evaluation.cost)
    return "";
  const auto clamped =
      std::find_if(fit.history.begin(), fit.history.end(),
                   [](const inverse::IterationRecord& r) { return r.stage == "clamped"; });
  std::string line = "the fit ends worse than the seed (cost " +
                     formatFixed(fit.seed_evaluation.cost, 1) + " -> " +
                     formatFixed(fit.final_evaluation.cost, 1) + ", AvgD " +
                     formatFixed(fit.seed_evaluation.mean_deviation_mm, 2) + " -> " +
                     formatFixed(fit.final_evaluation.mean_deviation_mm, 2) + " mm)";
  if (clamped != fit.history.end())
    return line + ": the seed lies outside the bounds, the fit started from it clamped into " +
           "them (cost " + formatFixed(clamped->cost, 1) +
           ") and did not get back below the seed's cost; widen --scale-bounds or give more "
           "--max-sims\n";
  return line + ": no point the fit reached inside the bounds was better; give more --max-sims\n";
}

bool optimiserRan(const inverse::FitOutcome& fit, const std::string& optimizer) {
  // A record of the optimiser's own beyond its start: not Ceres' iteration 0 (the start, closed
  // there when no stage before had), not NLopt's first evaluation (the start, cached).
  int sims_before = 0;  // forward runs when the optimiser started
  for (const inverse::IterationRecord& r : fit.history) {
    if (r.stage != optimizer) {
      if (r.stage.rfind("retry ", 0) == 0 || r.stage == "release") break;  // after it
      sims_before = r.forward_sims;
      continue;
    }
    if (r.iteration >= 1 && r.forward_sims > sims_before) return true;
  }
  return false;
}

std::string optimiserNoStep(const inverse::FitOutcome& fit, const std::string& optimizer) {
  if (optimiserRan(fit, optimizer)) return "";
  const bool prefits = fit.prefit_ran || fit.segment_prefit_ran || fit.tissue_prefit_ran;
  return (prefits ? "pre-fits only; " : "") + optimizer + " took no step";
}

std::string missedProlapseHint(const ValveCase& c, const FitCommandOptions& o,
                               const inverse::FitOutcome& fit, const ValveMetrics& fit_metrics) {
  if (!fit_metrics.has_tracings || fit_metrics.prolapse_reconstructed) return "";
  // In the tracings, not in the fit's planes.
  const std::vector<std::string> missing =
      prolapseMissing(fit_metrics.tracing_prolapse, fit_metrics.section_prolapse);
  if (missing.empty()) return "";  // the fit prolapses where the tracings do not: no remedy here
  const inverse::TissueRetry& retry = fit.tissue_retry;
  const Eigen::VectorXi segment = openStateSegments(c.mesh);
  int free_cords = 0, at_upper = 0, locked = 0;
  for (const Cord& cord : fit.fitted.cords) {
    // A cord without a segment ("?") is in none of the missing ones.
    if (std::find(missing.begin(), missing.end(), cordSegment(c, segment, cord)) == missing.end())
      continue;
    if (cord.locked) {
      ++locked;
      continue;
    }
    ++free_cords;
    at_upper += cord.scale() >= o.scale_bounds[1] - 1e-9 ? 1 : 0;
  }
  std::string hint =
      "the tracings show prolapse in " + joinSegments(missing) + ", the fitted closure does not: ";
  // The probe's section exists only when it ran (not with --no-uncertainty).
  const std::string locks = !fit.locked_probes.cords.empty()
                                ? "report.md, \"Locked cords\""
                                : "run without --no-uncertainty to probe them";
  if (free_cords == 0 && locked == 0) {
    hint += "no cord attaches there, so no cord length can make the flap";
  } else if (free_cords == 0) {
    hint += "every cord there is locked (" + locks + "); unlock them to let the fit move them";
  } else if (at_upper > 0) {
    hint += std::to_string(at_upper) + " of the " + std::to_string(free_cords) +
            " free cords there end at the upper scale bound " + formatWeight(o.scale_bounds[1]) +
            "; a higher one (--scale-bounds " + formatWeight(o.scale_bounds[0]) +
            ",HI) lets them lengthen further";
  } else if (fit.budget_spent && !optimiserRan(fit, o.optimizer)) {
    // The cords are where the pre-fits left them: the budget, not the cords, is the limit.
    hint += o.optimizer + " took no step, the budget being spent (" + fit.termination + ")" +
            (o.tissue_retry && !retry.ran && !retry.skipped.empty()
                 ? ", and softer tissue was not tried: the tissue retry did not run (" +
                       retry.skipped + ")"
                 : std::string()) +
            ": raise --max-sims";
  } else if (fit.tissue_prefit_ran) {
    hint += "neither the cords within the scale bounds nor the tissue pre-fit made the flap";
  } else if (retry.ran && !retry.error.empty()) {
    hint += "the tissue retry's fit failed (" + retry.error + ")";
  } else if (retry.ran && retry.tissue_changes.empty()) {
    hint +=
        "no free cord there reaches the upper scale bound, and no softer tissue there fitted "
        "the tracings better (the tissue retry)";
  } else if (retry.ran && !retry.kept && retry.missing_after.empty()) {
    hint += "softer tissue made the flap (the tissue retry: " + joined(retry.tissue_changes, "; ") +
            ") but fitted the tracings no better, so the fit keeps the cords alone (report.md, "
            "\"tissue retry\")";
  } else if (retry.ran) {
    hint +=
        "neither the cords within the scale bounds nor softer tissue there (the tissue retry) "
        "made the flap";
  } else if (!o.tissue_retry) {
    hint +=
        "no free cord there reaches the upper scale bound, so the flap may need softer "
        "tissue: try --tissue-prefit, or leave out --no-tissue-retry (docs/fitting.md, "
        "\"Tissue pre-fit\")";
  } else {
    hint +=
        "no free cord there reaches the upper scale bound, and softer tissue was not tried: "
        "the tissue " +
        std::string(o.tissue_prefit ? "pre-fit did not fit in --max-sims; raise it"
                                    : "retry did not run (" + retry.skipped + ")");
  }
  if (locked > 0 && free_cords > 0)
    hint += "; " + std::to_string(locked) + " cords there are locked (" + locks + ")";
  return hint + "\n";
}

nlohmann::json lockedProbeJson(const ValveCase& c, const inverse::FitOutcome& fit) {
  const inverse::LockedCordProbes& probes = fit.locked_probes;
  auto trialJson = [](const inverse::LockedCordTrial& trial) {
    nlohmann::json entry = {{"cords", trial.cords}};
    if (!trial.error.empty()) {
      entry["error"] = trial.error;
    } else {
      entry["rest_lengths_mm"] = trial.lengths_mm;
      entry["predicted_cost_drop"] = trial.predicted_drop;
      entry["data_cost"] = trial.data_cost;
      entry["mean_deviation_mm"] = trial.mean_deviation_mm;
    }
    return entry;
  };
  nlohmann::json cords = nlohmann::json::array(), segments = nlohmann::json::array();
  for (const inverse::LockedCordProbe& p : probes.cords) {
    nlohmann::json entry = {{"cord", p.cord}, {"slack", p.slack}, {"closed_span_mm", p.span_mm}};
    if (!p.slack) entry["trial"] = trialJson(p.trial);
    cords.push_back(entry);
  }
  for (const inverse::LockedSegmentProbe& p : probes.segments)
    segments.push_back(
        {{"segment", segmentName(c.mesh.leaflet_names, p.segment)}, {"trial", trialJson(p.trial)}});
  return {{"fit_data_cost", probes.fit_data_cost},
          {"relative_step", probes.relative_step},
          {"max_change", probes.max_change},
          {"fit_mean_deviation_mm", probes.fit_mean_deviation_mm},
          {"forward_sims", probes.forward_sims},
          {"unsettled_sims", probes.unsettled_sims},
          {"seconds", probes.seconds},
          {"cords", cords},
          {"segments", segments}};
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

namespace {

// A stage's markers in convergence.svg and its legend text (the stage's name in
// convergence.csv first). The one-point stages (the seed, the pre-fits, the slack release)
// are large and of distinct shapes, the optimiser's iterations smaller circles in the cost
// line's blue, its full-closure iterations after warm-started differences misled
// ("<optimizer>-full") vermillion squares; the tissue retry's ("retry <stage>") the same shapes
// in wine red.
PlotSeries stageSeries(const std::string& stage, const std::string& optimizer) {
  // The tissue retry's stages: the same shapes as the first optimisation's, in one colour.
  const std::string retry = "retry ";
  if (stage.rfind(retry, 0) == 0) {
    PlotSeries series = stageSeries(stage.substr(retry.size()), optimizer);
    series.label = retry + series.label;
    series.colour = "#882255";
    return series;
  }
  struct Style {
    const char* stage;
    const char* text;
    const char* colour;
    PlotMarker marker;
    double radius;
  };
  static const Style kStyles[] = {
      {"seed", "seed", "#000000", PlotMarker::kCircle, 5.0},
      {"clamped", "clamped: seed clamped into the bounds", "#999999", PlotMarker::kCircle, 5.0},
      {"prefit", "prefit: global pre-fit", "#CC79A7", PlotMarker::kSquare, 6.5},
      {"segments", "segments: segment pre-fit", "#009E73", PlotMarker::kDiamond, 6.0},
      {"tissue", "tissue: tissue pre-fit", "#56B4E9", PlotMarker::kTriangleDown, 6.5},
      {"release", "release: slack release", "#E69F00", PlotMarker::kTriangleUp, 6.5}};
  PlotSeries series;
  series.label = stage;
  series.markers = true;
  series.line = false;
  for (const Style& style : kStyles) {
    if (stage != style.stage) continue;
    series.label = style.text;
    series.colour = style.colour;
    series.marker = style.marker;
    series.marker_radius = style.radius;
    // A stage's one point often shares its closure with the optimiser's first iteration
    // and is surrounded by the optimiser's points.
    series.on_top = true;
    return series;
  }
  const std::string full = "-full";
  if (stage.size() > full.size() &&
      stage.compare(stage.size() - full.size(), full.size(), full) == 0) {
    series.label = stage + ": full closures";
    series.colour = "#D55E00";
    series.marker = PlotMarker::kSquare;
    series.marker_radius = 4.5;
  } else {
    // Ceres records its iterations; NLopt's methods, each evaluation.
    series.label = stage + (stage != optimizer     ? ""
                            : optimizer == "ceres" ? " iterations"
                                                   : " evaluations");
    series.colour = stage == optimizer ? "#0072B2" : "#56B4E9";
    series.marker_radius = 3.5;
  }
  return series;
}

}  // namespace

std::string convergenceSvg(const std::vector<IterationRecord>& history, const std::string& name) {
  // The cost as a line, the best cost dashed over it (equal to the cost wherever a step
  // improved, it would hide under it as a solid line), and each stage's points as markers of
  // their own shape and colour over both, one legend entry per stage.
  PlotSeries cost{"cost", {}, {}, false, true, false, "#0072B2"};
  PlotSeries best{"best so far", {}, {}, false, true, true, "#666666"};
  PlotSeries mean{"mean deviation (AvgD)", {}, {}, true, true, false, "#0072B2"};
  std::vector<std::string> stage_names;
  std::vector<PlotSeries> stages;  // in the order they first ran
  for (const IterationRecord& r : history) {
    cost.x.push_back(r.forward_sims), cost.y.push_back(r.cost);
    best.x.push_back(r.forward_sims), best.y.push_back(r.best_cost);
    mean.x.push_back(r.forward_sims), mean.y.push_back(r.mean_deviation_mm);
    const std::size_t k =
        std::find(stage_names.begin(), stage_names.end(), r.stage) - stage_names.begin();
    if (k == stage_names.size()) {
      stage_names.push_back(r.stage);
      stages.push_back(stageSeries(r.stage, name));
    }
    stages[k].x.push_back(r.forward_sims), stages[k].y.push_back(r.cost);
  }
  std::vector<PlotSeries> cost_series{cost, best};
  cost_series.insert(cost_series.end(), stages.begin(), stages.end());
  // The legends right of the frames, where they cover no point; both frames as wide, so that
  // the panels' x axes line up.
  constexpr double kLegendMargin = 190.0;
  const std::vector<PlotPanel> panels = {
      {"Fit cost (" + name + ")", "forward simulations", "cost (mm², log scale)", cost_series, true,
       kLegendMargin},
      {"Mean deviation to the tracings",
       "forward simulations",
       "mean deviation (mm)",
       {mean},
       false,
       kLegendMargin}};
  return svgLinePlots(panels, 1, 860, 320);
}

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

namespace {

// With --params scales+tips: each PM tip's fitted offset per axis, with its SD; "" when the fit
// has no tip parameter.
std::string tipTable(const inverse::FitOutcome& fit) {
  std::ostringstream md;
  for (std::size_t p = 0; p < fit.parameter_names.size(); ++p) {
    if (fit.parameter_is_scale[p]) continue;
    if (md.tellp() == 0)
      md << "## PM tips\n\nOffset of each tip coordinate from its seed position (mm, within "
            "--tip-box, pulled toward 0 by --tip-weight) and its SD from the Jacobian at the "
            "fit. An offset within "
         << formatWeight(kTipOffsetDeterminedSds)
         << " SD of zero is not determined by the tracings: the tip may as well have stayed "
            "where the seed put it, and on a synthetic case it can move away from the true tip "
            "(docs/fitting.md, \"What is weak\").\n\n"
            "| Parameter | Offset (mm) | ± SD (mm) | Determined |\n|---|---:|---:|---|\n";
    const Eigen::Index i = static_cast<Eigen::Index>(p);
    const bool known = fit.uncertainty.ok();
    md << "| " << fit.parameter_names[p] << " | " << formatFixed(fit.x(i), 3) << " | "
       << (known ? formatFixed(fit.uncertainty.sd(i), 3) : std::string("–"))
       << (known && fit.uncertainty.at_bound[p] ? " (at bound)" : "") << " | "
       << (!known                        ? "–"
           : tipOffsetDetermined(fit, p) ? "yes"
                                         : "no")
       << " |\n";
  }
  if (md.tellp() > 0) md << "\n";
  return md.str();
}

}  // namespace

bool tipOffsetDetermined(const inverse::FitOutcome& fit, std::size_t p) {
  const Eigen::Index i = static_cast<Eigen::Index>(p);
  return fit.uncertainty.ok() && !fit.parameter_is_scale[p] && !fit.uncertainty.at_bound[p] &&
         std::abs(fit.x(i)) > kTipOffsetDeterminedSds * fit.uncertainty.sd(i);
}

std::string tipOffsetsLine(const inverse::FitOutcome& fit) {
  int tips = 0, determined = 0;
  for (std::size_t p = 0; p < fit.parameter_is_scale.size(); ++p) {
    if (fit.parameter_is_scale[p]) continue;
    ++tips;
    determined += tipOffsetDetermined(fit, p) ? 1 : 0;
  }
  if (tips == 0 || !fit.uncertainty.ok()) return "";
  return "PM tips: " + std::to_string(determined) + " of " + std::to_string(tips) +
         " tip offsets determined (more than " + formatWeight(kTipOffsetDeterminedSds) +
         " SD from 0); for the others, no offset fits the tracings about as well "
         "(report.md, \"PM tips\")\n";
}

int slackCords(const inverse::FitOutcome& fit) {
  const Eigen::VectorXd& spans = fit.closed_spans;
  int count = 0;
  for (std::size_t i = 0; i < fit.fitted.cords.size(); ++i)
    count += slackAtSpan(spans(static_cast<Eigen::Index>(i)), fit.fitted.cords[i].rest_length);
  return count;
}

int identifiedCords(const inverse::FitOutcome& fit) {
  int count = 0;
  for (std::size_t c = 0; c < fit.cord_parameter.size(); ++c) {
    const int p = fit.cord_parameter[c];
    if (p < 0 || !fit.uncertainty.ok() || fit.uncertainty.at_bound[p]) continue;
    // A cord no tracing point moves with ("prior only" in the table) is not determined by the
    // data, however narrow the prior between determined neighbours makes its SD; nor is a cord
    // slack in the fitted closure whose parameter others determine (a group factor,
    // --params groups): the data bound its length from below only.
    if (fit.uncertainty.sensitivity(p) == 0.0) continue;
    const Eigen::Index i = static_cast<Eigen::Index>(c);
    if (i < fit.closed_spans.size() &&
        slackAtSpan(fit.closed_spans(i), fit.fitted.cords[c].rest_length))
      continue;
    if (fit.uncertainty.sd(p) < 0.03 * fit.x(p)) ++count;
  }
  return count;
}

int freeCords(const inverse::FitOutcome& fit) {
  int count = 0;
  for (int p : fit.cord_parameter) count += p >= 0 ? 1 : 0;
  return count;
}

std::string extraClosures(int closures, int unsettled) {
  return counted(closures, "extra closure") +
         (unsettled > 0 ? ", " + std::to_string(unsettled) + " unsettled" : "");
}

std::string fitReport(const ValveCase& c, const FitCommandOptions& o,
                      const inverse::FitOutcome& fit, const ValveMetrics& seed_metrics,
                      const ValveMetrics& fit_metrics) {
  std::ostringstream md;
  md << "# Cord fit: " << c.name << "\n\n";
  md << "- parameters: " << o.params << " (" << fit.x.size() << "), optimizer: " << o.optimizer
     << ", scale bounds [" << o.scale_bounds[0] << ", " << o.scale_bounds[1] << "]\n";
  if (o.params == "scales+tips")
    md << "- PM tip offsets: box ±" << o.tip_box_mm << " mm per axis, prior "
       << formatWeight(o.tip_weight) << " mm of residual per mm of offset (--tip-weight)\n";
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
  // Why a pre-fit did not run, or "" when it ran.
  auto notRun = [&](bool ran, bool applies) -> std::string {
    if (ran) return "";
    if (!o.prefit) return "disabled (--no-prefit)";
    if (!fit.prefit_skipped.empty()) return "skipped: " + fit.prefit_skipped;
    if (!applies) return "not run with --params " + o.params;
    if (fit.x.size() == 0) return "not run: no free cord";
    return "not run: --max-sims " + std::to_string(o.max_sims) + " leaves too few closures";
  };
  if (const std::string why = notRun(fit.prefit_ran, true); !why.empty())
    md << "- global pre-fit: " << why << "\n";
  else if (fit.prefit_kind_stage == inverse::KindStage::kNotAsked)
    md << "- global pre-fit factor: " << formatFixed(fit.prefit_factor, 3)
       << "; per kind: not run (--max-sims " << o.max_sims << " leaves too few closures)\n";
  else if (fit.prefit_kind_stage == inverse::KindStage::kOneKindFree)
    md << "- global pre-fit factor: " << formatFixed(fit.prefit_factor, 3)
       << "; per kind: not run (only one cord kind has free cords that are not manual)\n";
  else
    md << "- global pre-fit factor: " << formatFixed(fit.prefit_factor, 3)
       << "; per kind: primaries " << formatFixed(fit.prefit_primary_factor, 3) << ", secondaries "
       << formatFixed(fit.prefit_secondary_factor, 3) << "\n";
  const std::string segment_not_run = notRun(fit.segment_prefit_ran, o.params != "groups");
  md << "- segment pre-fit: "
     << (!segment_not_run.empty()             ? segment_not_run
         : fit.segment_prefit_changes.empty() ? std::string("no change")
                                              : joinSegments(fit.segment_prefit_changes))
     << "\n";
  if (o.tissue_prefit) {
    const std::string tissue_not_run = tissuePrefitNotRun(fit, o);
    md << "- tissue pre-fit (stiffness factor per segment): "
       << (!tissue_not_run.empty() ? tissue_not_run
           : fit.tissue_prefit_changes.empty()
               ? std::string("no change (uniform tissue kept)")
               : joinSegments(fit.tissue_prefit_changes) +
                     "; the cords were fitted on this tissue (tissue.json)")
       << "\n";
  }
  md << "- tissue retry: " << tissueRetryLine(fit, o) << "\n";
  md << "- slack release: " << slackReleaseLine(fit, o.slack_release, o.params) << "\n";
  // Ceres differentiates, and so does the uncertainty after any optimiser (NLopt's methods
  // themselves are derivative-free).
  const bool ceres = o.optimizer == "ceres";
  if (ceres || fit.uncertainty.ok()) {
    md << "- finite differences" << (ceres ? "" : " (the uncertainty's only)") << ": step "
       << o.fd_scale_step << " on a scale"
       << (o.params == "scales+tips" ? ", " + formatFixed(o.fd_tip_step_mm, 2) + " mm on a tip"
                                     : std::string())
       << (!o.fd_warm_start ? ", perturbed closures from the open state"
           : fit.switched_to_full_closures
               ? ", perturbed closures warm-started from the base closed state (--fd-warm) until "
                 "Ceres rejected two steps in a row, then from the open state"
               : ", perturbed closures warm-started from the base closed state (--fd-warm)")
       << (o.fd_slack_closures ? ", slack-only parameters closed too (--fd-slack-closures)"
                               : std::string())
       << "\n";
  }
  if (!o.settings_overrides.empty()) {
    md << "- simulator settings over the case's (--set):";
    for (const std::string& item : o.settings_overrides) md << " `" << item << "`";
    md << "\n";
  }
  md << "- forward simulations: " << fit.forward_sims + 1 << " (" << fit.forward_sims
     << " in the fit, 1 for the closure written out; metrics.json forward_sims), fit time: "
     << formatFixed(fit.seconds, 1) << " s, threads: " << o.threads << "\n";
  // Closures that reached the step cap (the terminal said so; the report did not).
  if (fit.unsettled_sims > 0)
    md << "- unsettled: " << fit.unsettled_sims << " of the fit's " << fit.forward_sims
       << " closures reached the step cap (max_steps) before the quasi-static criterion; each is "
          "the mean of its last steps (metrics.json unsettled_sims)\n";
  if (fit.final_evaluation.ok() && !fit.final_evaluation.converged)
    md << "- **the fit's best closure did not settle**: it reached the step cap and is the "
          "mean of its last steps; its numbers are less certain than a settled closure's\n";
  const std::string no_step = optimiserNoStep(fit, o.optimizer);
  md << "- termination: " << fit.termination << (no_step.empty() ? "" : "; " + no_step) << "\n";
  md << "- cost: seed " << fit.seed_evaluation.cost << ", fit " << fit.final_evaluation.cost
     << "\n";
  if (const std::string note = worseThanSeedNote(fit); !note.empty())
    md << "- **" << note.substr(0, note.size() - 1) << "**\n";
  md << "\n";
  md << "## Table 1: seed vs fit\n\n"
     << table1Header("Cord set") << table1Row("seed", seed_metrics) << table1Row("fit", fit_metrics)
     << "\n";
  md << "Prolapse segments: tracings " << joinSegments(fit_metrics.tracing_prolapse.segments)
     << "; in the tracing planes: seed " << joinSegments(seed_metrics.section_prolapse.segments)
     << ", fit " << joinSegments(fit_metrics.section_prolapse.segments)
     << " (Table 1 compares these); tissue: seed "
     << joinSegments(seed_metrics.mesh_prolapse.segments) << ", fit "
     << joinSegments(fit_metrics.mesh_prolapse.segments) << "\n\n";
  if (const std::string hint = missedProlapseHint(c, o, fit, fit_metrics); !hint.empty())
    md << hint << "\n";
  if (seed_metrics.orifice.samples > 0 && fit_metrics.orifice.samples > 0) {
    char line[260];
    std::snprintf(line, sizeof line,
                  "Orifice covered seen en face (orifice_coverage in metrics.json; the leaflets "
                  "as tissue, mid-surface ± %.2g mm): seed %.1f %% (open %.0f mm²), fit %.1f %% "
                  "(open %.0f mm²) of %.0f mm².\n\n",
                  fit_metrics.orifice.tissue_radius_mm, 100.0 * seed_metrics.orifice.coverage(),
                  seed_metrics.orifice.open_area_mm2, 100.0 * fit_metrics.orifice.coverage(),
                  fit_metrics.orifice.open_area_mm2, fit_metrics.orifice.orifice_area_mm2);
    md << line;
  }
  md << "![Seed (dashed) and fitted closures against the tracings, one panel per image plane]"
        "(sections.svg)\n\n";
  md << "![The fitted closed valve from the atrium, the open orifice in red](enface.svg)\n\n";
  md << tipTable(fit);
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
        "span closes the valve the same way: the tracings bound it from below only. ± SD "
        "\"prior only\": no tracing point moves with the cord, so its length is the prior's "
        "(the seed's and its neighbours'), not a measurement. The SD is local: it says how far a "
        "cord can move while the others stay, not whether another combination of lengths fits "
        "the tracings as well (a flap held by other cords); on a synthetic case, compare's "
        "per-cord table against the truth shows where a fit took another way. "
     << slackCords(fit) << " of " << fit.fitted.cords.size() << " cords are slack. "
     << (fit.uncertainty.ok()
             ? std::to_string(identifiedCords(fit)) + " of " + std::to_string(freeCords(fit)) +
                   " free cords are determined to better than 3 % (taut, moving the data, not at "
                   "a scale bound, SD below 3 %)."
             : std::string("How well the data determine the cords was not "
                           "computed."))
     << "\n\n"
     << cordTable(c, fit) << "\n"
     << lockedCordSection(c, fit);
  return md.str();
}

}  // namespace chordfit::cli
