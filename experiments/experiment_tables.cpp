#include "experiments/experiment_tables.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <utility>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/counted.h"
#include "core/joined.h"
#include "core/svg_line_plot.h"
#include "experiments/acceptance_table.h"
#include "experiments/result_fields.h"

namespace chordfit::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Attachment distance bins (mm) of the recovery table; 3 mm is issue 5's acceptance bound
// ("cords attached within 3 mm of a tracing plane").
const std::vector<double> kDistanceBinEdges = {0.0, 1.0, 3.0, 6.0};
constexpr double kWithinOfBest = 0.10;  // optimiser comparison: within 10 % of the best AvgD

std::string binName(std::size_t bin) {
  if (bin + 1 < kDistanceBinEdges.size()) {
    return fixed(kDistanceBinEdges[bin], 0) + "–" + fixed(kDistanceBinEdges[bin + 1], 0) + " mm";
  }
  return "≥ " + fixed(kDistanceBinEdges[bin], 0) + " mm";
}

std::size_t binOf(double distance) {
  std::size_t bin = 0;
  while (bin + 1 < kDistanceBinEdges.size() && distance >= kDistanceBinEdges[bin + 1]) ++bin;
  return bin;
}

class Merger {
 public:
  Merger(const ExperimentPlan& plan, const ExperimentConfig& config, const fs::path& results,
         const MergeOptions& options)
      : plan_(plan),
        config_(config),
        results_(results),
        timing_(!options.no_timing),
        plan_options_(options.plan_options),
        plan_id_(options.plan_id.empty() ? planId(plan) : options.plan_id) {
    // Every job file is checked before any table is written: a bad one (truncated, another
    // job's, without a key) stops the merge naming it, with the tables as they were.
    for (const JobSpec& job : plan.jobs) {
      const fs::path file = results / "jobs" / (job.id + ".json");
      if (!fs::exists(file)) {
        summary_.missing_jobs.push_back(job.id);
        continue;
      }
      json result;
      if (const std::string problem = jobResultProblem(file, job.id, &result); !problem.empty())
        throw std::runtime_error(file.string() + ": " + problem +
                                 "; remove it (run_experiments run makes it again) or restore it");
      results_by_job_[job.id] = std::move(result);
      ++summary_.jobs_found;
    }
  }

  // Every table is made before any is written, so a merge that fails while making them (an
  // exception from a table) leaves the tables of the last merge, not a mix of old and new.
  MergeSummary run() {
    table1();
    acceptance();
    optimizers();
    recovery();
    sensitivity();
    index();
    for (const auto& [name, text] : pending_) writeFileAtomically(results_ / name, text);
    return summary_;
  }

 private:
  const json* result(const std::string& case_id, const std::string& tag) const {
    const auto it = results_by_job_.find(case_id + "__" + tag);
    return it == results_by_job_.end() ? nullptr : &it->second;
  }

  void write(const std::string& name, const std::string& text) {
    pending_.emplace_back(name, text);
    summary_.written_files.push_back(name);
  }

  // The jobs of these cases without a result; a long list is left to index.md.
  std::string missingSection(const std::set<std::string>& case_ids) const {
    constexpr std::size_t kListedAtMost = 12;
    std::vector<std::string> missing;
    for (const std::string& id : summary_.missing_jobs) {
      if (case_ids.count(id.substr(0, id.find("__")))) missing.push_back(id);
    }
    if (missing.empty()) return "";
    std::string md = "\n**Missing**: " + std::to_string(missing.size()) +
                     " job(s) of these cases failed or did not run, so they have no row";
    if (missing.size() > kListedAtMost) return md + " (listed in index.md).\n";
    for (std::size_t k = 0; k < missing.size(); ++k) md += (k ? ", `" : ": `") + missing[k] + "`";
    return md + ".\n";
  }

  // Table 1 of every preset x seed case: the five methods and the noise floor.
  void table1() {
    std::string md =
        "# Table 1 analogue\n\nDeviation of the closed valve from the tracings (mm), valve area, "
        "and whether the prolapse is reconstructed: the closed mesh cut by the tracing planes and "
        "read like the tracings shows the same segments as the tracings (*in the planes* vs "
        "*tracings*; *tissue*: every mesh vertex by its open-state position, a diagnostic). "
        "*noise floor*: the true closed state on the fine truth mesh against its own tracings "
        "(no fit can go below it).\n\n| Case | Method | Area (mm²) | MinD | MedD | MaxD | AvgD ± "
        "SD | Prolapse Recon. | In the planes | Tracings | Tissue | Sims |" +
        std::string(timing_ ? " Wall (s) |" : "") +
        "\n|---|---|---:|---:|---:|---:|---:|---|---|---|---|---:|" + (timing_ ? "---:|" : "") +
        "\n";
    std::string csv = table1CsvHeader(timing_);
    // Per method: AvgD, MaxD, prolapse reconstructed, sims, wall (for the summary).
    std::map<std::string, std::vector<const json*>> by_label;
    std::vector<std::string> label_order;
    std::set<std::string> cases;
    for (const std::string& preset : config_.presets) {
      for (int seed : config_.seeds) {
        const std::string case_id = baseCaseId(preset, seed);
        cases.insert(case_id);
        for (const JobSpec& job : plan_.jobs) {
          if (job.case_id != case_id || !isTable1Method(job)) continue;
          const json* r = result(case_id, methodTag(job));
          if (r == nullptr) continue;
          if (!by_label.count(job.label)) label_order.push_back(job.label);
          by_label[job.label].push_back(r);
          addTable1Row(case_id, job.label, methodTag(job), r->at("metrics"),
                       number(*r, "forward_sims"), number(*r, "wall_seconds"), md, csv);
          if (job.method == Method::kTruth && r->contains("noise_floor")) {
            addTable1Row(case_id, "noise floor", "noise_floor", r->at("noise_floor"), kNaN, kNaN,
                         md, csv);
          }
        }
      }
    }
    md += missingSection(cases);
    md +=
        "\n## Summary over cases\n\n| Method | Cases | AvgD mean (range) | MaxD mean (range) | "
        "Prolapse reconstructed | Median sims |" +
        std::string(timing_ ? " Median wall (s) |" : "") + "\n|---|---:|---|---|---:|---:|" +
        (timing_ ? "---:|" : "") + "\n";
    for (const std::string& label : label_order) {
      std::vector<double> avg, max, sims, wall;
      int reconstructed = 0;
      for (const json* r : by_label[label]) {
        avg.push_back(number(r->at("metrics"), "mean_mm"));
        max.push_back(number(r->at("metrics"), "max_mm"));
        sims.push_back(number(*r, "forward_sims"));
        wall.push_back(number(*r, "wall_seconds"));
        reconstructed += yesNo(r->at("metrics")) == "yes";
      }
      auto range = [](const std::vector<double>& v) {
        return mdNumber(mean(v)) + " (" + mdNumber(*std::min_element(v.begin(), v.end())) + "–" +
               mdNumber(*std::max_element(v.begin(), v.end())) + ")";
      };
      md += "| " + label + " | " + std::to_string(avg.size()) + " | " + range(avg) + " | " +
            range(max) + " | " + std::to_string(reconstructed) + "/" + std::to_string(avg.size()) +
            " | " + mdNumber(quantile(sims, 0.5), 0) + " |" +
            (timing_ ? " " + mdNumber(quantile(wall, 0.5), 1) + " |" : "") + "\n";
    }
    write("table1.md", md);
    write("table1.csv", csv);
  }

  // Issue 5's acceptance criteria per case (acceptance_table.h).
  void acceptance() {
    const AcceptanceTables tables = acceptanceTables(
        config_,
        [this](const std::string& case_id, const std::string& tag) { return result(case_id, tag); },
        [this](const std::string& case_id, const std::string& tag) {
          for (const JobSpec& job : plan_.jobs)
            if (job.case_id == case_id && methodTag(job) == tag) return true;
          return false;
        },
        timing_);
    write("acceptance.md", tables.markdown);
    write("acceptance.csv", tables.csv);
  }

  static bool isTable1Method(const JobSpec& job) {
    return job.method != Method::kFit || job.optimizer == "ceres";
  }

  void addTable1Row(const std::string& case_id, const std::string& label, const std::string& tag,
                    const json& m, double sims, double wall, std::string& md,
                    std::string& csv) const {
    md += "| " + case_id + " | " + label + " | " + mdNumber(number(m, "area_mm2"), 0) + " | " +
          mdNumber(number(m, "min_mm")) + " | " + mdNumber(number(m, "median_mm")) + " | " +
          mdNumber(number(m, "max_mm")) + " | " + mdNumber(number(m, "mean_mm")) + " ± " +
          mdNumber(number(m, "sd_mm")) + " | " + yesNo(m) + " | " +
          segmentsOrNone(m, "section_prolapse_segments") + " | " +
          segmentsOrNone(m, "tracing_prolapse_segments") + " | " +
          segmentsOrNone(m, "prolapse_segments") + " | " + mdNumber(sims, 0) + " |" +
          (timing_ ? " " + mdNumber(wall, 1) + " |" : "") + "\n";
    const CaseSpec& c = findCase(plan_, case_id);
    csv += case_id + "," + c.preset + "," + std::to_string(c.seed) + "," + tag + "," + label + "," +
           fixed(number(m, "area_mm2"), 2) + "," + fixed(number(m, "min_mm"), 4) + "," +
           fixed(number(m, "median_mm"), 4) + "," + fixed(number(m, "max_mm"), 4) + "," +
           fixed(number(m, "mean_mm"), 4) + "," + fixed(number(m, "sd_mm"), 4) + "," + yesNo(m) +
           "," + segments(m, "section_prolapse_segments", " ") + "," +
           segments(m, "prolapse_segments", " ") + "," +
           segments(m, "tracing_prolapse_segments", " ") + "," + fixed(sims, 0) +
           (timing_ ? "," + fixed(wall, 2) : "") + "\n";
  }

  // Equal budget per-cord fits: final AvgD, when each came within 10 % of the best.
  void optimizers() {
    std::string md =
        "# Optimiser comparison\n\nPer-cord rest-length scales from the heuristic, every "
        "optimiser with the same forward-simulation budget (" +
        std::to_string(config_.max_sims) +
        "). *Sims to 10 %*: forward simulations until the running AvgD first came within 10 % "
        "of the best final AvgD of all optimisers on that case.\n\n| Case | Optimiser | Final "
        "AvgD (mm) | Final MaxD (mm) | Sims used | Sims to 10 % |" +
        std::string(timing_ ? " Wall (s) |" : "") + "\n|---|---|---:|---:|---:|---:|" +
        (timing_ ? "---:|" : "") + "\n";
    std::string csv = optimizersCsvHeader(timing_);
    std::vector<PlotPanel> panels;
    std::set<std::string> cases;
    for (const std::string& preset : config_.optimizer_presets) {
      const std::string case_id = baseCaseId(preset, config_.seeds.front());
      cases.insert(case_id);
      PlotPanel panel{case_id, "forward simulations", "AvgD (mm)", {}, false};
      double best = std::numeric_limits<double>::infinity();
      for (const std::string& optimizer : config_.optimizers) {
        if (const json* r = result(case_id, "fit_scales_" + optimizer)) {
          best = std::min(best, number(r->at("metrics"), "mean_mm"));
        }
      }
      for (const std::string& optimizer : config_.optimizers) {
        const json* r = result(case_id, "fit_scales_" + optimizer);
        if (r == nullptr) continue;
        PlotSeries series{optimizer, {}, {}, false, true};
        double reached = kNaN;
        const json& trace = r->at("convergence");
        for (std::size_t k = 0; k < trace.at("forward_sims").size(); ++k) {
          // A failed closure's row has no AvgD (NaN in convergence.csv, null in the job's JSON):
          // a gap in the trace.
          const json& sims_cell = trace.at("forward_sims")[k];
          const json& avg_cell = trace.at("mean_mm")[k];
          if (!sims_cell.is_number() || !avg_cell.is_number()) continue;
          const double sims = sims_cell.get<double>();
          const double avg = avg_cell.get<double>();
          series.x.push_back(sims);
          series.y.push_back(avg);
          if (!std::isfinite(reached) && avg <= (1.0 + kWithinOfBest) * best) reached = sims;
        }
        panel.series.push_back(series);
        const json& m = r->at("metrics");
        const double wall = number(*r, "wall_seconds");
        md += "| " + case_id + " | " + optimizer + " | " + mdNumber(number(m, "mean_mm")) + " | " +
              mdNumber(number(m, "max_mm")) + " | " + mdNumber(number(*r, "forward_sims"), 0) +
              " | " + (std::isfinite(reached) ? mdNumber(reached, 0) : "not reached") + " |" +
              (timing_ ? " " + mdNumber(wall, 1) + " |" : "") + "\n";
        csv += case_id + "," + optimizer + "," + std::to_string(config_.max_sims) + "," +
               fixed(number(m, "mean_mm"), 4) + "," + fixed(number(m, "max_mm"), 4) + "," +
               fixed(number(*r, "forward_sims"), 0) + "," + fixed(reached, 0) +
               (timing_ ? "," + fixed(wall, 2) : "") + "\n";
      }
      panels.push_back(panel);
    }
    md += missingSection(cases);
    md += "\nPlot: `optimizers.svg` (AvgD of the iterates against forward simulations).\n";
    write("optimizers.md", md);
    write("optimizers.csv", csv);
    write("optimizers.svg", svgLinePlots(panels, 2));
  }

  // Rest-length error by attachment distance, pooled over the Table 1 cases.
  void recovery() {
    std::string md =
        "# Parameter recovery\n\n|rest length / true rest length − 1| per cord, pooled over the "
        "Table 1 cases, by the distance of the cord's attachment (true closed state) from the "
        "nearest tracing plane. Ruptured cords are left out (their true length only means "
        "\"never taut\").\n\n| Method | Attachment distance | Cords | Median error (%) | 90th "
        "percentile (%) |\n|---|---|---:|---:|---:|\n";
    std::string csv = recoveryCsvHeader();
    std::string cords_csv =
        "case,method,label,cord,segment,kind,plane_distance_mm,rest_length_mm,"
        "true_rest_length_mm,relative_error\n";
    PlotPanel scatter{"Rest-length error against attachment distance",
                      "distance from nearest "
                      "tracing plane (mm)",
                      "|relative error| (%)",
                      {},
                      false};
    std::set<std::string> cases;
    std::vector<std::string> label_order;
    std::map<std::string, std::vector<std::vector<double>>> binned;  // label -> bin -> errors
    std::map<std::string, std::vector<double>> near;                 // label -> errors <= 3 mm
    std::map<std::string, PlotSeries> series;
    for (const std::string& preset : config_.presets) {
      for (int seed : config_.seeds) {
        const std::string case_id = baseCaseId(preset, seed);
        cases.insert(case_id);
        for (const JobSpec& job : plan_.jobs) {
          if (job.case_id != case_id || job.method == Method::kTruth || !isTable1Method(job)) {
            continue;
          }
          const json* r = result(case_id, methodTag(job));
          if (r == nullptr) continue;
          if (!binned.count(job.label)) {
            label_order.push_back(job.label);
            binned[job.label].resize(kDistanceBinEdges.size());
            series[job.label] = PlotSeries{job.label, {}, {}, true, false};
          }
          for (const json& c : r->at("cords")) {
            const double distance = c.at("plane_distance_mm").get<double>();
            const double error = c.at("relative_error").get<double>();
            cords_csv += case_id + "," + methodTag(job) + "," + job.label + "," +
                         std::to_string(c.at("index").get<int>()) + "," +
                         c.at("segment").get<std::string>() + "," +
                         c.at("kind").get<std::string>() + "," + fixed(distance, 3) + "," +
                         fixed(c.at("rest_length_mm").get<double>(), 4) + "," +
                         fixed(c.at("true_rest_length_mm").get<double>(), 4) + "," +
                         (c.at("ruptured").get<bool>() ? "ruptured" : fixed(error, 5)) + "\n";
            if (c.at("ruptured").get<bool>()) continue;
            binned[job.label][binOf(distance)].push_back(100.0 * std::abs(error));
            if (distance <= 3.0) near[job.label].push_back(100.0 * std::abs(error));
            series[job.label].x.push_back(distance);
            series[job.label].y.push_back(100.0 * std::abs(error));
          }
        }
      }
    }
    for (const std::string& label : label_order) {
      auto row = [&](const std::string& bin, const std::vector<double>& errors) {
        md += "| " + label + " | " + bin + " | " + std::to_string(errors.size()) + " | " +
              mdNumber(quantile(errors, 0.5), 1) + " | " + mdNumber(quantile(errors, 0.9), 1) +
              " |\n";
        csv += label + "," + bin + "," + std::to_string(errors.size()) + "," +
               fixed(quantile(errors, 0.5), 3) + "," + fixed(quantile(errors, 0.9), 3) + "\n";
      };
      std::vector<double> all;
      for (std::size_t b = 0; b < kDistanceBinEdges.size(); ++b) {
        row(binName(b), binned[label][b]);
        all.insert(all.end(), binned[label][b].begin(), binned[label][b].end());
      }
      row("≤ 3 mm", near[label]);
      row("all", all);
      scatter.series.push_back(series[label]);
    }
    md += missingSection(cases);
    md += "\nPlot: `recovery.svg`; every cord: `recovery_cords.csv`.\n";
    write("recovery.md", md);
    write("recovery.csv", csv);
    write("recovery_cords.csv", cords_csv);
    write("recovery.svg", svgLinePlots({scatter}, 1, 720, 420));
  }

  // AvgD and recovery against tracing noise and plane count (one preset, first seed).
  void sensitivity() {
    std::string md =
        "# Sensitivity\n\n" + config_.sensitivity_preset + ", seed " +
        std::to_string(config_.seeds.front()) + "; tracing noise σ varied at " +
        std::to_string(config_.planes) +
        " planes, plane count varied at σ = " + fixed(config_.noise_mm, 1) +
        " mm. Recovery: median |rest-length error| of the per-cord fit.\n\n| Sweep "
        "| Value | Heuristic AvgD | Per-cord AvgD | Per-cord MaxD | Noise floor AvgD | "
        "Recovery, all (%) | Recovery, ≤ 3 mm (%) |\n|---|---:|---:|---:|---:|---:|---:|"
        "---:|\n";
    std::string csv = sensitivityCsvHeader();
    std::vector<PlotPanel> panels;
    std::set<std::string> cases;
    // Each sweep value is its own case (the variant ids of makePlan: "_noise0.6", "_planes3";
    // the plan's own noise and plane count are the base case). A value whose case the plan
    // does not hold (--cases, --presets, --seeds, --methods) has no row: it once took the base
    // case's numbers, so every row of a one-case merge showed the same fit.
    const std::string base_id = baseCaseId(config_.sensitivity_preset, config_.seeds.front());
    auto inPlan = [&](const std::string& id) {
      return std::any_of(plan_.cases.begin(), plan_.cases.end(),
                         [&](const CaseSpec& c) { return c.id == id; });
    };
    std::vector<std::string> left_out;  // "noise σ 0.6 (prolapse-P2_s1_noise0.6)"
    int rows = 0;
    auto sweep = [&](const std::string& name, const std::string& unit,
                     const std::vector<double>& values, auto case_of) {
      PlotPanel avg_panel{"AvgD against " + name, name + unit, "AvgD (mm)", {}, false};
      PlotPanel rec_panel{"Recovery against " + name, name + unit, "median |error| (%)", {}, false};
      PlotSeries heuristic{"heuristic", {}, {}, true, true},
          fitted{"per-cord fit", {}, {}, true, true}, floor{"noise floor", {}, {}, true, true},
          rec_all{"all cords", {}, {}, true, true},
          rec_near{"≤ 3 mm from a plane", {}, {}, true, true};
      for (double value : values) {
        const std::string case_id = case_of(value);
        const std::string v = fixed(value, name == "planes" ? 0 : 1);
        if (!inPlan(case_id)) {
          left_out.push_back(name + " " + v + " (" + case_id + ")");
          continue;
        }
        ++rows;
        cases.insert(case_id);
        const json* h = result(case_id, "heuristic");
        const json* f = result(case_id, "fit_scales_ceres");
        const json* t = result(case_id, "truth");
        const double h_avg = h ? number(h->at("metrics"), "mean_mm") : kNaN;
        const double f_avg = f ? number(f->at("metrics"), "mean_mm") : kNaN;
        const double f_max = f ? number(f->at("metrics"), "max_mm") : kNaN;
        const double floor_avg =
            t && t->contains("noise_floor") ? number(t->at("noise_floor"), "mean_mm") : kNaN;
        const double all = f ? 100.0 * quantile(cordErrors(*f), 0.5) : kNaN;
        const double close = f ? 100.0 * quantile(cordErrors(*f, 3.0), 0.5) : kNaN;
        md += "| " + name + " | " + v + " | " + mdNumber(h_avg) + " | " + mdNumber(f_avg) + " | " +
              mdNumber(f_max) + " | " + mdNumber(floor_avg) + " | " + mdNumber(all, 1) + " | " +
              mdNumber(close, 1) + " |\n";
        csv += name + "," + v + "," + case_id + "," + fixed(h_avg, 4) + "," + fixed(f_avg, 4) +
               "," + fixed(f_max, 4) + "," + fixed(floor_avg, 4) + "," + fixed(all, 3) + "," +
               fixed(close, 3) + "\n";
        for (PlotSeries* s : {&heuristic, &fitted, &floor, &rec_all, &rec_near})
          s->x.push_back(value);
        heuristic.y.push_back(h_avg);
        fitted.y.push_back(f_avg);
        floor.y.push_back(floor_avg);
        rec_all.y.push_back(all);
        rec_near.y.push_back(close);
      }
      avg_panel.series = {heuristic, fitted, floor};
      rec_panel.series = {rec_all, rec_near};
      panels.push_back(avg_panel);
      panels.push_back(rec_panel);
    };
    sweep("noise σ", " (mm)", config_.noise_sweep, [&](double sigma) {
      char s[32];
      std::snprintf(s, sizeof s, "_noise%g", sigma);
      return sigma == config_.noise_mm ? base_id : base_id + s;
    });
    std::vector<double> planes(config_.plane_sweep.begin(), config_.plane_sweep.end());
    sweep("planes", "", planes, [&](double k) {
      return static_cast<int>(k) == config_.planes
                 ? base_id
                 : base_id + "_planes" + std::to_string(static_cast<int>(k));
    });
    if (rows == 0) {
      // A plan restricted to other cases: no sweep to tabulate.
      write("sensitivity.md", md + "\nNo rows: the plan does not hold the sweeps' cases (" +
                                  base_id + " and its variants).\n");
      write("sensitivity.csv", csv);
      write("sensitivity.svg", svgLinePlots({}, 2));
      return;
    }
    md += missingSection(cases);
    if (!left_out.empty()) {
      md +=
          "\n**Not in the plan** (rows left out; the run's --cases, --presets, --seeds or "
          "--methods chose other cases): " +
          joined(left_out, ", ") + ".\n";
    }
    md += "\nPlot: `sensitivity.svg`.\n";
    write("sensitivity.md", md);
    write("sensitivity.csv", csv);
    write("sensitivity.svg", svgLinePlots(panels, 2));
  }

  // The distinct values of a job-result key, each in backticks with its count of jobs and a space,
  // then a newline ("unknown" when there are none); a result without the key counts as `missing`,
  // or is left out when `missing` is empty.
  std::string recordedValues(const char* key, const std::string& missing) const {
    std::map<std::string, int> values;  // value -> jobs
    for (const auto& [id, r] : results_by_job_) {
      if (r.contains(key))
        ++values[r.at(key).get<std::string>()];
      else if (!missing.empty())
        ++values[missing];
    }
    std::string md;
    for (const auto& [v, jobs] : values)
      md += "`" + v + "` (" + std::to_string(jobs) + (jobs == 1 ? " job) " : " jobs) ");
    return md + (values.empty() ? "unknown\n" : "\n");
  }

  void index() {
    std::string md = "# Benchmark experiment results\n\nMade by `run_experiments merge` from " +
                     std::to_string(summary_.jobs_found) + " of " +
                     std::to_string(plan_.jobs.size()) + " job results (`jobs/*.json`), " +
                     counted(plan_.cases.size(), "case") +
                     ". See experiments/README.md, "
                     "\"Benchmark experiments\".\n\n";
    if (!plan_options_.empty())
      md += kPlanOptionsLine + ("`" + plan_options_ + "`") + kPlanIdMark + plan_id_ + "`\n\n";
    md += "Revision(s) of the chordfit that made the results: " + recordedValues("revision", "");
    // Wall times compare only within one machine (docs/performance.md); results made before
    // jobs recorded their machine have none.
    md += "Machine(s) the jobs ran on: " + recordedValues("machine", "not recorded");
    md +=
        "\nFiles: table1.md/.csv, acceptance.md/.csv, optimizers.md/.csv/.svg, "
        "recovery.md/.csv/.svg, "
        "recovery_cords.csv, sensitivity.md/.csv/.svg.\n";
    if (!summary_.missing_jobs.empty()) {
      md += "\n## Missing jobs (" + std::to_string(summary_.missing_jobs.size()) + ")\n\n";
      for (const std::string& id : summary_.missing_jobs) md += "- `" + id + "`\n";
    }
    write("index.md", md);
  }

  const ExperimentPlan& plan_;
  const ExperimentConfig& config_;
  fs::path results_;
  bool timing_;
  std::string plan_options_;
  std::string plan_id_;
  std::map<std::string, json> results_by_job_;
  std::vector<std::pair<std::string, std::string>> pending_;  // name, text: written by run()
  MergeSummary summary_;
};

}  // namespace

std::string table1CsvHeader(bool timing) {
  return std::string(
             "case,preset,seed,method,label,area_mm2,min_mm,median_mm,max_mm,mean_mm,sd_mm,"
             "prolapse_reconstructed,section_prolapse_segments,prolapse_segments,"
             "tracing_prolapse_segments,forward_sims") +
         (timing ? ",wall_seconds" : "") + "\n";
}

std::string optimizersCsvHeader(bool timing) {
  return std::string(
             "case,optimizer,budget_sims,final_mean_mm,final_max_mm,forward_sims,"
             "sims_to_within_10pct_of_best") +
         (timing ? ",wall_seconds" : "") + "\n";
}

std::string recoveryCsvHeader() {
  return "label,attachment_distance,cords,median_abs_error_pct,p90_abs_error_pct\n";
}

std::string sensitivityCsvHeader() {
  return "sweep,value,case,heuristic_mean_mm,fit_mean_mm,fit_max_mm,noise_floor_mean_mm,"
         "recovery_median_pct_all,recovery_median_pct_within_3mm\n";
}

MergeSummary mergeResults(const ExperimentPlan& plan, const ExperimentConfig& config,
                          const fs::path& results, const MergeOptions& options) {
  return Merger(plan, config, results, options).run();
}

}  // namespace chordfit::experiments
