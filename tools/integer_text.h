// The integer values of the command line in the forms a case's integer settings take
// (docs/case-format.md): plain digits, or an integral number in decimal or exponent form
// ("1e3", "400.0", "+3", "007"). Always base 10: CLI11 alone reads "077" as octal 63 and
// accepts "0x40", which no JSON reader of the project does.
#pragma once

#include <optional>
#include <string>

namespace chordfit::cli {

// `text` as plain decimal digits with a '-' for a negative value and no leading zeros
// ("1e3" -> "1000", "+007" -> "7", "-0" -> "0", "2.50e1" -> "25"), the value exact however
// long (a 20-digit seed keeps every digit); nullopt when `text` is not a number written in
// decimal, or is not a whole one ("2.5", "abc", "0x40", "1e-1"). Blanks around it are ignored.
// An exponent beyond 100 gives a text of over 100 digits, to be refused as out of range.
std::optional<std::string> canonicalInteger(const std::string& text);

// -1, 0 or 1 as the integer `a` is below, equal to or above `b`, both canonicalInteger texts.
int compareIntegerTexts(const std::string& a, const std::string& b);

}  // namespace chordfit::cli
