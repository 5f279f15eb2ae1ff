// ASCII case folding for keywords and file extensions (locale-independent).
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

}  // namespace chordfit
