// Strings joined by a separator, for messages, reports and tables ("A2, P2", "P3 0.3; A2 0.1").
#pragma once

#include <string>
#include <vector>

namespace chordfit {

inline std::string joined(const std::vector<std::string>& strings, const std::string& separator) {
  std::string text;
  for (const std::string& s : strings) text += (text.empty() ? "" : separator) + s;
  return text;
}

}  // namespace chordfit
