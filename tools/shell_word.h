// A word for a command line a note suggests the user paste into a POSIX shell ("edit-cords
// 'my case' --unlock 3 ..."): unchanged when it holds only characters no shell treats
// specially, else in single quotes, an embedded quote written as '\'' (POSIX.1-2017, Shell
// Command Language 2.2.3: nothing is special inside single quotes but the quote itself).
#pragma once

#include <string>

namespace chordfit::cli {

inline std::string shellWord(const std::string& word) {
  const auto plain = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
           std::string("_-./,:=@%+").find(c) != std::string::npos;
  };
  bool quote = word.empty();
  for (const char c : word) quote = quote || !plain(c);
  if (!quote) return word;
  std::string out = "'";
  for (const char c : word) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace chordfit::cli
