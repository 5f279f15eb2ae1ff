// ASCII text helpers for keywords, file extensions and fields (locale-independent): case
// folding and trimming.
#pragma once

#include <algorithm>
#include <cctype>
#include <string>

namespace chordfit {

inline std::string asciiLowercase(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// `text` without the blanks (spaces, tabs, line ends) at either end.
inline std::string trimmed(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = text.find_last_not_of(" \t\r\n");
  return text.substr(first, last - first + 1);
}

}  // namespace chordfit
