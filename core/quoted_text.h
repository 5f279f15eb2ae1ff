// Text from an input file as an error message quotes it. A corrupt or binary file can put any
// bytes where a number or a keyword was expected; echoed as they are, NUL bytes, escape
// sequences and broken UTF-8 garbled the terminal and hid the rest of the message.
#pragma once

#include <cstddef>
#include <string>

namespace chordfit {

// Characters of a quoted value shown before it is cut with "…".
constexpr std::size_t kMaxQuotedCharacters = 40;

// `text` as a message may show it: every byte that is not printable text (a control character,
// C0 or C1, DEL, or a byte that is not part of well-formed UTF-8) written as \xNN, and the
// whole cut after `max_characters` characters with "…". Printable UTF-8 (°, é) stays as it is.
std::string shownText(const std::string& text, std::size_t max_characters = kMaxQuotedCharacters);

// shownText in double quotes: "\"" + shownText(text, max_characters) + "\"". A file name is
// shown whole (std::string::npos): cut, it would no longer say which file.
std::string quotedText(const std::string& text, std::size_t max_characters = kMaxQuotedCharacters);

}  // namespace chordfit
