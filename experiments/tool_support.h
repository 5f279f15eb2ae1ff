// Pieces shared by the small experiment tools (calibrate_cohort, mesh_convergence,
// coarse_start): argument parsing by hand (CLI11 is confined to tools/main.cpp for build time)
// and table cells.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "core/cohort_presets.h"

namespace chordfit::tool_support {

// The whole of `text` as a number (strtod syntax); false for "", "1x" or "x".
inline bool parseNumber(const std::string& text, double& value) {
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return !text.empty() && *end == '\0';
}

// A whole number >= 1 (seeds, step caps): "1.5" or "0" is an error, not rounded.
inline bool parsePositiveInteger(const std::string& text, double& value) {
  return parseNumber(text, value) && value >= 1.0 && value == std::floor(value) && value < 1e9;
}

// A comma-separated list of seeds (whole numbers >= 1); on failure `bad` is the bad item.
inline bool parseSeedList(const std::string& text, std::vector<std::uint64_t>& seeds,
                          std::string& bad) {
  seeds.clear();
  std::istringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    double value = 0.0;
    if (!parsePositiveInteger(item, value)) {
      bad = item;
      return false;
    }
    seeds.push_back(static_cast<std::uint64_t>(value));
  }
  bad = text;
  return !seeds.empty();
}

// A comma-separated list of positive, finite lengths; on failure `bad` is the bad item.
inline bool parseLengthList(const std::string& text, std::vector<double>& lengths,
                            std::string& bad) {
  lengths.clear();
  std::istringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    double value = 0.0;
    if (!parseNumber(item, value) || !(value > 0.0) || !std::isfinite(value)) {
      bad = item;
      return false;
    }
    lengths.push_back(value);
  }
  bad = text;
  return !lengths.empty();
}

// The first argument of every cohort experiment: a preset's name, or --help (-h). Returns the
// named preset; otherwise null, with `exit_code` what the program ends with: 0 after printing
// `usage` for --help, else `usage_error`'s code for a missing or unknown preset.
inline const CohortPreset* presetArgument(int argc, char** argv, const char* usage,
                                          int (*usage_error)(const std::string&), int& exit_code) {
  if (argc < 2) {
    exit_code = usage_error("expected a preset name");
    return nullptr;
  }
  const std::string first = argv[1];
  if (first == "--help" || first == "-h") {
    std::cout << usage;
    exit_code = 0;
    return nullptr;
  }
  const CohortPreset* preset = findCohortPreset(first);
  if (!preset) {
    exit_code = usage_error("unknown preset \"" + first + "\" (" + cohortPresetNames() + ")");
  }
  return preset;
}

// "A2 P2", or "–" for none: a list of segment names as one table cell.
inline std::string joinedNames(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : " ") + n;
  return text.empty() ? "–" : text;
}

}  // namespace chordfit::tool_support
