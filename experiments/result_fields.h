// Reading the per-job result files (results/jobs/<job>.json, experiment_jobs.h) and formatting
// their numbers for the merged tables: shared by the tables of `merge`.
#pragma once

#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace chordfit::experiments {

// What makes results/jobs/<job_id>.json unusable as that job's result: unreadable, not JSON
// (e.g. truncated), another job's (a file copied under another name), or without a key every
// job writes; "" when usable. `result` receives the parsed file when given.
std::string jobResultProblem(const std::filesystem::path& file, const std::string& job_id,
                             nlohmann::json* result = nullptr);

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// "%.*f"; "" for NaN or infinity.
std::string fixed(double value, int digits);
// As fixed, with "–" for a missing value (Markdown cells).
std::string mdNumber(double value, int digits = 2);
// j[key] as a number, NaN when missing or not a number.
double number(const nlohmann::json& j, const char* key);
// The string array j[key] joined by `separator` ("" when missing).
std::string segments(const nlohmann::json& j, const char* key, const char* separator);
// Markdown cell of the segment list j[key]: "P2, A2", "none" for an empty list, "–" when
// missing or null.
std::string segmentsOrNone(const nlohmann::json& j, const char* key);
// metrics.prolapse_reconstructed as "yes" / "no" ("" when not a boolean).
std::string yesNo(const nlohmann::json& metrics);
// Linear-interpolation quantile (type 7); NaN for an empty sample.
double quantile(std::vector<double> values, double q);
double mean(const std::vector<double>& values);
// |relative rest-length error| of a result's non-ruptured cords, optionally only those
// attached within `max_distance` (mm) of a tracing plane.
// taut_only: only the cords marked taut in the true closed state ("taut_in_truth"; results
// without the mark give none).
std::vector<double> cordErrors(const nlohmann::json& result, double max_distance = kNaN,
                               bool taut_only = false);

}  // namespace chordfit::experiments
