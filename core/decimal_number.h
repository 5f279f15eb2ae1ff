// A number as a person or a spreadsheet writes it in a text file or an option: decimal, an
// optional sign and exponent ("-12.5", "+3", "1e-3"), nothing around it. std::strtod also
// takes hexadecimal ("0x10" read as 16), "inf", "nan" and leading blanks, none of which a
// coordinate or a scale is meant to be.
#pragma once

#include <charconv>
#include <cmath>
#include <string>
#include <system_error>

namespace chordfit {

// True, with `value` set, when the whole of `text` is a finite decimal number.
inline bool parseDecimal(const std::string& text, double& value) {
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+') {  // from_chars takes '-' but not '+'
    ++first;
    if (first != last && (*first == '+' || *first == '-')) return false;  // "+-1"
  }
  const auto [end, error] = std::from_chars(first, last, value, std::chars_format::general);
  return error == std::errc() && end == last && std::isfinite(value);
}

}  // namespace chordfit
