// Minimal CSV reading for the tables chordfit itself writes (no quoting, no embedded commas).
#pragma once

#include <sstream>
#include <string>
#include <vector>

namespace chordfit {

// Rows of comma-separated cells; a trailing comma gives a trailing empty cell.
inline std::vector<std::vector<std::string>> parseSimpleCsv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::istringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    rows.push_back(cells);
  }
  return rows;
}

}  // namespace chordfit
