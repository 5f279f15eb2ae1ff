#include "tools/truth_recovery.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/json_fields.h"
#include "core/metrics.h"
#include "tools/command_support.h"

namespace chordfit::cli {

namespace {

// A warning, not an error: the comparison itself does not need the truth.
std::nullopt_t ignoreTruth(const std::filesystem::path& file, const std::string& what) {
  printWarning("%s: %s; compared without the truth\n", file.string().c_str(), what.c_str());
  return std::nullopt;
}

}  // namespace

std::optional<CaseTruth> readCaseTruth(const std::filesystem::path& case_dir) {
  const std::filesystem::path file = case_dir / "truth" / "truth.json";
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return std::nullopt;
  std::string text;
  if (!readWholeFile(file, text)) return ignoreTruth(file, cannotBeRead(file));
  Diagnostics diagnostics;  // the first problem (a syntax error, a duplicate key) is named
  const std::optional<nlohmann::json> parsed = parseJson(text, file.string(), diagnostics);
  if (!parsed) {
    const Problem& p = diagnostics.problems().front();
    return ignoreTruth(file, (p.where.empty() ? "" : p.where + ": ") + p.what);
  }
  const nlohmann::json& truth = *parsed;
  const auto number = [](const nlohmann::json& j, const char* key) {
    return j.is_object() && j.contains(key) && j[key].is_number();
  };
  if (!truth.is_object() || !truth.contains("cords") || !truth["cords"].is_array())
    return ignoreTruth(file, "cords: expected an array");
  CaseTruth result;
  for (std::size_t i = 0; i < truth["cords"].size(); ++i) {
    const nlohmann::json& c = truth["cords"][i];
    if (!number(c, "true_rest_length_mm") || !(c["true_rest_length_mm"].get<double>() > 0.0))
      return ignoreTruth(
          file, "cords[" + std::to_string(i) + "].true_rest_length_mm: expected a positive number");
    TrueCord cord;
    cord.rest_length_mm = c["true_rest_length_mm"].get<double>();
    if (c.contains("ruptured") && !c["ruptured"].is_boolean())
      return ignoreTruth(file, "cords[" + std::to_string(i) + "].ruptured: expected true or false");
    cord.ruptured = c.value("ruptured", false);
    if (c.contains("case_vertex") && c["case_vertex"].is_number_integer())
      cord.case_vertex = c["case_vertex"].get<int>();
    cord.taut = number(c, "true_closed_tension_n") && c["true_closed_tension_n"].get<double>() > 0;
    result.cords.push_back(cord);
  }
  if (truth.contains("tips") && truth["tips"].is_array()) {
    for (const nlohmann::json& t : truth["tips"]) {
      const nlohmann::json p = t.is_object() ? t.value("true_position", nlohmann::json()) : nullptr;
      if (!p.is_array() || p.size() != 3 || !p[0].is_number() || !p[1].is_number() ||
          !p[2].is_number())
        return ignoreTruth(file, "tips: each needs a true_position [x, y, z]");
      result.tip_positions.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
      const nlohmann::json h = t.value("case_heuristic_position", nlohmann::json());
      if (h.is_array() && h.size() == 3 && h[0].is_number() && h[1].is_number() && h[2].is_number())
        result.case_heuristic_tip_positions.emplace_back(h[0].get<double>(), h[1].get<double>(),
                                                         h[2].get<double>());
    }
    // All or nothing: a partial list cannot say whether a set's tips are the heuristic's.
    if (result.case_heuristic_tip_positions.size() != result.tip_positions.size())
      result.case_heuristic_tip_positions.clear();
  }
  // The noise floor is context only: a missing or unreadable metrics.json leaves it NaN.
  std::string metrics_text;
  if (readWholeFile(case_dir / "truth" / "metrics.json", metrics_text)) {
    const nlohmann::json metrics = nlohmann::json::parse(metrics_text, nullptr, false);
    if (number(metrics, "mean_mm")) result.noise_floor_mm = metrics["mean_mm"].get<double>();
  }
  return result;
}

TruthRecovery recoveryAgainstTruth(const CordSet& set, const CaseTruth& truth) {
  TruthRecovery r;
  if (set.cords.size() != truth.cords.size()) {
    r.problem = std::to_string(set.cords.size()) + " cords against the truth's " +
                std::to_string(truth.cords.size());
    return r;
  }
  // Cords pair with the truth's by index: a set of the same count in another order (or for
  // another mesh) would be compared cord against the wrong cord.
  for (std::size_t i = 0; i < set.cords.size(); ++i) {
    const int expected = truth.cords[i].case_vertex;
    if (expected >= 0 && set.cords[i].vertex != expected) {
      r.problem = "cord " + std::to_string(i) + " attaches at vertex " +
                  std::to_string(set.cords[i].vertex) + ", the truth's at " +
                  std::to_string(expected) + " (not the case's cords in the case's order)";
      return r;
    }
  }
  std::vector<double> all, taut;
  for (std::size_t i = 0; i < set.cords.size(); ++i) {
    const TrueCord& t = truth.cords[i];
    if (t.ruptured) {
      r.signed_error_pct.push_back(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    r.signed_error_pct.push_back(100.0 * (set.cords[i].rest_length / t.rest_length_mm - 1.0));
    const double error = std::abs(r.signed_error_pct.back());
    all.push_back(error);
    if (t.taut) taut.push_back(error);
  }
  r.cords = static_cast<int>(all.size());
  r.taut_cords = static_cast<int>(taut.size());
  r.median_error_pct = median(all);
  r.median_error_taut_pct = median(taut);
  if (set.tips.size() == truth.tip_positions.size()) {
    r.heuristic_tips = truth.case_heuristic_tip_positions.size() == set.tips.size();
    for (std::size_t k = 0; k < set.tips.size(); ++k) {
      r.max_tip_offset_mm =
          std::max(r.max_tip_offset_mm, (set.tips[k].position - truth.tip_positions[k]).norm());
      // cords.json keeps full precision: an unmoved tip reads back as the same numbers.
      if (r.heuristic_tips)
        r.heuristic_tips =
            (set.tips[k].position - truth.case_heuristic_tip_positions[k]).norm() < 1e-9;
    }
  } else {
    r.max_tip_offset_mm = std::numeric_limits<double>::quiet_NaN();
  }
  return r;
}

}  // namespace chordfit::cli
