// Pieces shared by the small experiment tools (calibrate_cohort, mesh_convergence,
// coarse_start): argument parsing by hand (CLI11 is confined to tools/main.cpp for build time)
// and table cells.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

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

// "A2 P2", or "–" for none: a list of segment names as one table cell.
inline std::string joinedNames(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : " ") + n;
  return text.empty() ? "–" : text;
}

}  // namespace chordfit::tool_support
