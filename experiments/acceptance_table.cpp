#include "experiments/acceptance_table.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "core/cohort_presets.h"
#include "core/joined.h"
#include "experiments/result_fields.h"

namespace chordfit::experiments {

using nlohmann::json;

namespace {

constexpr const char* kFitTag = "fit_scales_ceres";  // the per-cord Ceres fit of Table 1

bool isPathological(const std::string& preset) {
  const CohortPreset* p = findCohortPreset(preset);
  return p != nullptr && !p->intended_prolapse.empty();
}

// "✓" / "✗" for a criterion, "–" when it does not apply or cannot be judged.
std::string mark(bool applies, bool known, bool met) {
  if (!applies || !known) return "–";
  return met ? "✓" : "✗";
}

// The preset's intended prolapse segments, sorted as the metrics list them.
std::vector<std::string> intendedSegments(const std::string& preset) {
  const CohortPreset* p = findCohortPreset(preset);
  std::vector<std::string> segments =
      p != nullptr ? p->intended_prolapse : std::vector<std::string>{};
  std::sort(segments.begin(), segments.end());
  return segments;
}

std::vector<std::string> segmentList(const json& metrics, const char* key) {
  if (!metrics.contains(key) || !metrics.at(key).is_array()) return {};
  auto segments = metrics.at(key).get<std::vector<std::string>>();
  std::sort(segments.begin(), segments.end());
  return segments;
}

// Cords of a fit result: all, and the ruptured ones (no true rest length: the flail presets'
// truth lengthens them tenfold, so the recovery leaves them out).
struct CordCounts {
  int total = 0, ruptured = 0;
};

CordCounts cordCounts(const json& result) {
  CordCounts counts;
  for (const json& c : result.at("cords")) {
    ++counts.total;
    counts.ruptured += c.at("ruptured").get<bool>();
  }
  return counts;
}

// The make-case options a job's case was made with, as the job recorded them.
std::string caseOptions(const json& result) {
  return "--edge " + fixed(number(result, "edge_mm"), 2) + " --planes " +
         fixed(number(result, "planes"), 0) + " --noise " + fixed(number(result, "noise_mm"), 2) +
         " --dropout " + fixed(number(result, "dropout"), 2);
}

struct Tally {
  int met = 0, judged = 0;
  void add(bool applies, bool known, bool ok) {
    if (!applies || !known) return;
    ++judged;
    met += ok;
  }
  std::string text() const {
    return std::to_string(met) + " of " + std::to_string(judged) + " cases";
  }
};

}  // namespace

std::string acceptanceCsvHeader(bool timing) {
  return std::string(
             "case,preset,pathological,heuristic_mean_mm,fit_mean_mm,reduction_pct,"
             "noise_floor_mean_mm,fit_over_noise_floor,truth_on_case_mesh_mean_mm,"
             "tracing_prolapse_segments,fit_section_prolapse_segments,prolapse_reconstructed,"
             "fit_tissue_prolapse_segments,tissue_prolapse_reconstructed,"
             "intended_prolapse_segments,prolapse_as_intended,cords,ruptured_cords,"
             "cords_within_3mm,recovery_median_pct_within_3mm,taut_cords_within_3mm,"
             "recovery_median_pct_taut_within_3mm,forward_sims,tissue_retry_kept") +
         (timing ? ",wall_seconds" : "") + "\n";
}

AcceptanceTables acceptanceTables(const ExperimentConfig& config, const ResultLookup& result,
                                  const PlanLookup& planned, bool timing,
                                  const AcceptanceThresholds& t) {
  AcceptanceTables out;
  out.csv = acceptanceCsvHeader(timing);
  std::string rows;
  Tally reduction, floor, prolapse, intended, tissue, recovery, taut_recovery;
  int planned_cases = 0;                   // with a heuristic and a fit job in the plan
  std::vector<std::string> missing;        // cases without a heuristic or fit result
  std::vector<std::string> missing_truth;  // judged, but without the truth's floor columns
  std::vector<std::string> intended_misses;
  int pooled_cords = 0, pooled_ruptured = 0, pooled_near = 0;
  std::set<std::string> case_options;  // as the fit jobs recorded them
  for (const std::string& preset : config.presets) {
    for (int seed : config.seeds) {
      const std::string case_id = baseCaseId(preset, seed);
      if (!planned(case_id, "heuristic") || !planned(case_id, kFitTag)) continue;
      ++planned_cases;
      const json* heuristic = result(case_id, "heuristic");
      const json* fit = result(case_id, kFitTag);
      const json* truth = result(case_id, "truth");
      if (heuristic == nullptr || fit == nullptr) {
        missing.push_back(case_id);
        continue;
      }
      if (truth == nullptr) missing_truth.push_back(case_id);
      case_options.insert(caseOptions(*fit));
      const bool pathological = isPathological(preset);
      const json& m = fit->at("metrics");
      const double before = number(heuristic->at("metrics"), "mean_mm");
      const double after = number(m, "mean_mm");
      const double reduction_pct = 100.0 * (1.0 - after / before);
      const double noise_floor = truth != nullptr && truth->contains("noise_floor")
                                     ? number(truth->at("noise_floor"), "mean_mm")
                                     : kNaN;
      const double truth_case = truth != nullptr ? number(truth->at("metrics"), "mean_mm") : kNaN;
      const double over_floor = after / noise_floor;
      // Table 1's criterion: the closed mesh in the tracing planes against the tracings.
      const std::string reconstructed = yesNo(m);
      // The tissue judgement (core/metrics.h), a diagnostic; absent from older results.
      const bool has_tissue = m.contains("tissue_prolapse_reconstructed") &&
                              m.at("tissue_prolapse_reconstructed").is_boolean();
      const bool tissue_ok = has_tissue && m.at("tissue_prolapse_reconstructed").get<bool>();
      // Item 7's "right segment(s)": the preset's, against the fit's closed mesh in the
      // tracing planes (the tracings themselves miss a prolapse some planes do not cut).
      const std::vector<std::string> wanted = intendedSegments(preset);
      const bool has_sections =
          m.contains("section_prolapse_segments") && m.at("section_prolapse_segments").is_array();
      const bool as_intended =
          has_sections && segmentList(m, "section_prolapse_segments") == wanted;
      if (has_sections && !as_intended) intended_misses.push_back(case_id);
      const CordCounts cords = cordCounts(*fit);
      const std::vector<double> near = cordErrors(*fit, t.near_plane_mm);
      pooled_cords += cords.total;
      pooled_ruptured += cords.ruptured;
      pooled_near += static_cast<int>(near.size());
      const double recovery_pct = 100.0 * quantile(near, 0.5);
      // The same over the cords taut in the true closed state: the only ones whose rest
      // length the closed valve depends on (a slack cord's is bounded below only).
      const std::vector<double> taut = cordErrors(*fit, t.near_plane_mm, true);
      const double taut_pct = taut.empty() ? kNaN : 100.0 * quantile(taut, 0.5);
      // The fit ran again on softer tissue and kept it (fit's tissue retry): the tissue it found,
      // "" when it did not (or the result predates the retry).
      const bool retry_kept =
          fit->contains("tissue_retry") && fit->at("tissue_retry").value("kept", false);
      const std::string retry_tissue =
          retry_kept
              ? joined(fit->at("tissue_retry").at("tissue").get<std::vector<std::string>>(), "; ")
              : "";
      const double sims = number(*fit, "forward_sims");
      const double wall = number(*fit, "wall_seconds");

      reduction.add(pathological, std::isfinite(reduction_pct),
                    reduction_pct >= t.min_reduction_pct);
      floor.add(true, std::isfinite(over_floor), over_floor <= t.max_over_noise_floor);
      prolapse.add(true, !reconstructed.empty(), reconstructed == "yes");
      intended.add(true, has_sections, as_intended);
      tissue.add(true, has_tissue, tissue_ok);
      recovery.add(true, std::isfinite(recovery_pct), recovery_pct <= t.max_recovery_median_pct);
      taut_recovery.add(true, std::isfinite(taut_pct), taut_pct <= t.max_recovery_median_pct);

      rows +=
          "| " + case_id + " | " + mdNumber(before) + " → " + mdNumber(after) + " | " +
          mdNumber(reduction_pct, 0) + " % " +
          mark(pathological, std::isfinite(reduction_pct), reduction_pct >= t.min_reduction_pct) +
          " | " + mdNumber(noise_floor) + " | " + mdNumber(over_floor, 1) + "× " +
          mark(true, std::isfinite(over_floor), over_floor <= t.max_over_noise_floor) + " | " +
          mdNumber(truth_case) + " (" + mdNumber(truth_case / noise_floor, 1) + "×) | " +
          segmentsOrNone(m, "tracing_prolapse_segments") + " / " +
          segmentsOrNone(m, "section_prolapse_segments") + " " +
          mark(true, !reconstructed.empty(), reconstructed == "yes") +
          (retry_kept ? " (tissue retry: " + retry_tissue + ")" : "") + " | " +
          segmentsOrNone(m, "prolapse_segments") + " " + mark(true, has_tissue, tissue_ok) + " | " +
          (wanted.empty() ? std::string("none") : joined(wanted, ", ")) + " " +
          mark(true, has_sections, as_intended) + " | " + mdNumber(recovery_pct, 1) + " % (" +
          std::to_string(near.size()) + " of " + std::to_string(cords.total) +
          (cords.ruptured > 0 ? ", " + std::to_string(cords.ruptured) + " ruptured" : "") + ") " +
          mark(true, std::isfinite(recovery_pct), recovery_pct <= t.max_recovery_median_pct) +
          " | " + mdNumber(taut_pct, 1) + " % (" + std::to_string(taut.size()) + ") " +
          mark(true, std::isfinite(taut_pct), taut_pct <= t.max_recovery_median_pct) + " | " +
          mdNumber(sims, 0) + (timing ? " | " + mdNumber(wall, 1) : "") + " |\n";
      out.csv += case_id + "," + preset + "," + (pathological ? "yes" : "no") + "," +
                 fixed(before, 4) + "," + fixed(after, 4) + "," + fixed(reduction_pct, 1) + "," +
                 fixed(noise_floor, 4) + "," + fixed(over_floor, 3) + "," + fixed(truth_case, 4) +
                 "," + segments(m, "tracing_prolapse_segments", " ") + "," +
                 segments(m, "section_prolapse_segments", " ") + "," + reconstructed + "," +
                 segments(m, "prolapse_segments", " ") + "," +
                 (has_tissue ? (tissue_ok ? "yes" : "no") : "") + "," + joined(wanted, " ") + "," +
                 (has_sections ? (as_intended ? "yes" : "no") : "") + "," +
                 std::to_string(cords.total) + "," + std::to_string(cords.ruptured) + "," +
                 std::to_string(near.size()) + "," + fixed(recovery_pct, 2) + "," +
                 std::to_string(taut.size()) + "," + fixed(taut_pct, 2) + "," + fixed(sims, 0) +
                 "," + (fit->contains("tissue_retry") ? (retry_kept ? "yes" : "no") : "") +
                 (timing ? "," + fixed(wall, 2) : "") + "\n";
    }
  }
  const std::string fit_options =
      "--params scales --optimizer ceres --max-sims " + std::to_string(config.max_sims) +
      " --threads " + std::to_string(config.fit_threads) + (config.fd_warm ? " --fd-warm" : "") +
      (config.scale_bounds ? " --scale-bounds " + fixed(config.scale_bounds->first, 2) + "," +
                                 fixed(config.scale_bounds->second, 2)
                           : "");
  out.markdown =
      "# Acceptance of the per-cord fit\n\n"
      "Per-cord Ceres fit from the heuristic (`" +
      std::string(kFitTag) + "` jobs: `chordfit fit " + fit_options + "`, the merge's plan) on " +
      (case_options.size() == 1 ? "cases made by `chordfit make-case " + *case_options.begin() + "`"
                                : std::string("cases made with differing options")) +
      " (make-case's default edge is 1.5 mm; docs/fitting.md reports a run at it). "
      "Criteria: AvgD reduced by ≥ " +
      fixed(t.min_reduction_pct, 0) + " % against the heuristic (pathological presets); AvgD ≤ " +
      fixed(t.max_over_noise_floor, 1) +
      "× the noise floor (the true closed state of the fine truth mesh against its own "
      "tracings); the prolapse in the right segments, judged two ways: *tracings / fit in their "
      "planes* (Table 1's criterion: the closed mesh cut by the tracing planes and read like the "
      "tracings shows the tracings' segments) and *preset* (the same planes show exactly the "
      "segments the preset makes prolapse; the noisy tracings miss some a plane cuts); the tissue "
      "judgement, every vertex localised by its open-state position, is a diagnostic; median "
      "|rest-length error| ≤ " +
      fixed(t.max_recovery_median_pct, 0) + " % over the cords attached within " +
      fixed(t.near_plane_mm, 0) +
      " mm of a tracing plane (in brackets: how many, of how many cords; ruptured cords have "
      "no true rest length and are left out); *taut in the truth*: the same over "
      "those of them taut in the true closed state, the only ones whose length the closed valve "
      "depends on (a diagnostic: a slack cord's rest length is bounded below only, "
      "docs/fitting.md \"Uncertainty\"). *True cords on the case mesh*: the true "
      "rest lengths and PM tips closed on the (coarser) case mesh; its excess over the noise "
      "floor is discretisation, not fitting. It is no bound on the per-cord fit, which keeps "
      "the heuristic's tips and lets the lengths make up for them (docs/fitting.md, \"Without "
      "the mesh error\"). *(tissue retry: …)* after a prolapse verdict: the fit's closure with the "
      "cords alone missed a prolapse of the tracings, so the fit ran again from its pre-fits "
      "with the tissue pre-fit and kept that, on the tissue named (docs/fitting.md, \"Tissue "
      "retry\").\n\n"
      "| Case | AvgD heuristic → fit (mm) | Reduction | Noise floor (mm) | Fit / floor | True "
      "cords on the case mesh (mm, / floor) | Prolapse: tracings / fit in their planes | Fit "
      "tissue | Preset | Recovery ≤ "
      "3 mm | Recovery, taut in the truth | Sims |" +
      std::string(timing ? " Wall (s) |" : "") +
      "\n|---|---|---|---:|---|---|---|---|---|---|---|---:|" + (timing ? "---:|" : "") + "\n" +
      rows + "\n**Met:** AvgD reduction " + reduction.text() + "; within " +
      fixed(t.max_over_noise_floor, 1) + "× the noise floor " + floor.text() +
      "; prolapse reconstructed " + prolapse.text() + " (tissue judgement: " + tissue.text() +
      "); prolapse in the preset's segments " + intended.text() +
      (intended_misses.empty() ? std::string()
                               : " (missed: " + joined(intended_misses, ", ") + ")") +
      "; recovery " + recovery.text() + " (cords taut in the truth: " + taut_recovery.text() +
      "). Cords within " + fixed(t.near_plane_mm, 0) +
      " mm of a plane: " + std::to_string(pooled_near) + " of " +
      std::to_string(pooled_cords - pooled_ruptured) + " unruptured (" +
      std::to_string(pooled_ruptured) + " ruptured left out).\n";
  if (planned_cases == 0) {
    out.markdown +=
        "\n**No case to judge**: no case of this merge's plan has both a heuristic "
        "and a per-cord Ceres fit job (`" +
        std::string(kFitTag) + "`; see its --cases, --methods).\n";
  }
  if (!missing.empty()) {
    out.markdown += "\n**Not judged** (no heuristic or fit result): " + joined(missing, ", ") +
                    "; the counts above leave them out.\n";
  }
  if (!missing_truth.empty()) {
    out.markdown += "\n**No truth result** for " + joined(missing_truth, ", ") +
                    ": their noise floor, fit / floor and true-cords columns are blank and the "
                    "floor criterion leaves them out.\n";
  }
  return out;
}

}  // namespace chordfit::experiments
