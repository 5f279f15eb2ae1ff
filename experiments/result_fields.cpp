#include "experiments/result_fields.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/atomic_file.h"
#include "core/joined.h"

namespace chordfit::experiments {

using nlohmann::json;

std::string jobResultProblem(const std::filesystem::path& file, const std::string& job_id,
                             json* result) {
  std::string text;
  if (!readWholeFile(file, text)) return "cannot be read";
  json parsed = json::parse(text, nullptr, false);
  if (parsed.is_discarded() || !parsed.is_object())
    return "is not a JSON object (truncated or edited?)";
  if (!parsed.contains("job") || !parsed.at("job").is_string()) return "has no \"job\"";
  if (parsed.at("job").get<std::string>() != job_id) {
    return "is the result of job " + parsed.at("job").get<std::string>() +
           " (a file copied under another name?)";
  }
  // Keys runJob writes for every method that the tables read.
  for (const char* key : {"case", "method", "forward_sims"}) {
    if (!parsed.contains(key)) return std::string("has no \"") + key + "\"";
  }
  if (!parsed.contains("metrics") || !parsed.at("metrics").is_object())
    return "has no \"metrics\" object";
  if (!parsed.contains("cords") || !parsed.at("cords").is_array()) return "has no \"cords\" array";
  if (result) *result = std::move(parsed);
  return "";
}

std::string fixed(double value, int digits) {
  if (!std::isfinite(value)) return "";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

std::string mdNumber(double value, int digits) {
  const std::string s = fixed(value, digits);
  return s.empty() ? "–" : s;
}

double number(const json& j, const char* key) {
  return j.contains(key) && j.at(key).is_number() ? j.at(key).get<double>() : kNaN;
}

std::string segments(const json& j, const char* key, const char* separator) {
  if (!j.contains(key) || !j.at(key).is_array()) return "";
  return joined(j.at(key).get<std::vector<std::string>>(), separator);
}

std::string segmentsOrNone(const json& j, const char* key) {
  if (!j.contains(key) || !j.at(key).is_array()) return "–";
  const std::string text = segments(j, key, ", ");
  return text.empty() ? "none" : text;
}

std::string yesNo(const json& metrics) {
  const json& r = metrics.at("prolapse_reconstructed");
  return r.is_boolean() ? (r.get<bool>() ? "yes" : "no") : "";
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return kNaN;
  std::sort(values.begin(), values.end());
  const double h = (values.size() - 1) * q;
  const std::size_t lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (h - lo) * (values[hi] - values[lo]);
}

double mean(const std::vector<double>& values) {
  if (values.empty()) return kNaN;
  double sum = 0.0;
  for (double v : values) sum += v;
  return sum / values.size();
}

std::vector<double> cordErrors(const json& result, double max_distance, bool taut_only) {
  std::vector<double> errors;
  for (const json& c : result.at("cords")) {
    if (c.at("ruptured").get<bool>()) continue;
    if (taut_only && !(c.contains("taut_in_truth") && c.at("taut_in_truth").get<bool>())) continue;
    if (std::isfinite(max_distance) && c.at("plane_distance_mm").get<double>() > max_distance) {
      continue;
    }
    errors.push_back(std::abs(c.at("relative_error").get<double>()));
  }
  return errors;
}

}  // namespace chordfit::experiments
