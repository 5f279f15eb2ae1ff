#include "tools/integer_text.h"

#include <algorithm>
#include <cstddef>
#include <string_view>

#include "core/text_case.h"

namespace chordfit::cli {

namespace {

bool isDigit(char c) { return c >= '0' && c <= '9'; }

// The digits of `text` from `at` on, advancing `at` past them.
std::string digitsFrom(const std::string& text, std::size_t& at) {
  const std::size_t start = at;
  while (at < text.size() && isDigit(text[at])) ++at;
  return text.substr(start, at - start);
}

}  // namespace

std::optional<std::string> canonicalInteger(const std::string& input) {
  const std::string text = trimmed(input);
  std::size_t at = 0;
  bool negative = false;
  if (at < text.size() && (text[at] == '+' || text[at] == '-')) negative = text[at++] == '-';
  const std::string whole = digitsFrom(text, at);
  std::string fraction;
  if (at < text.size() && text[at] == '.') fraction = digitsFrom(text, ++at);
  if (whole.empty() && fraction.empty()) return std::nullopt;
  long exponent = 0;
  if (at < text.size() && (text[at] == 'e' || text[at] == 'E')) {
    ++at;
    bool exponent_negative = false;
    if (at < text.size() && (text[at] == '+' || text[at] == '-'))
      exponent_negative = text[at++] == '-';
    const std::string exponent_digits = digitsFrom(text, at);
    if (exponent_digits.empty()) return std::nullopt;
    // Only whether it passes 100 matters beyond that (every value but 0 is then out of any
    // integer type's range), so at most 4 significant digits are read: 1e999999999 stays short.
    const std::string significant = exponent_digits.substr(
        std::min(exponent_digits.find_first_not_of('0'), exponent_digits.size()));
    exponent = significant.size() > 4 ? 10000 : std::stol("0" + significant);
    if (exponent_negative) exponent = -exponent;
  }
  if (at != text.size()) return std::nullopt;

  // value = digits x 10^shift, digits the whole and fraction digits together.
  std::string digits = whole + fraction;
  long shift = exponent - static_cast<long>(fraction.size());
  if (shift < 0) {
    // Whole only when the digits shifted out are zeros (or the value is zero).
    const std::size_t cut = static_cast<std::size_t>(-shift);
    const std::size_t keep = digits.size() > cut ? digits.size() - cut : 0;
    if (digits.find_first_not_of('0', keep) != std::string::npos) return std::nullopt;
    digits.resize(keep);
    shift = 0;
  }
  digits = digits.substr(std::min(digits.find_first_not_of('0'), digits.size()));
  if (digits.empty()) return std::string("0");  // "-0", "0e5", "0.000"
  constexpr long kMostZeros = 101;              // past every integer type's range already
  digits.append(static_cast<std::size_t>(std::min(shift, kMostZeros)), '0');
  return negative ? "-" + digits : digits;
}

int compareIntegerTexts(const std::string& a, const std::string& b) {
  const bool a_negative = !a.empty() && a[0] == '-', b_negative = !b.empty() && b[0] == '-';
  if (a_negative != b_negative) return a_negative ? -1 : 1;
  // Magnitudes: no leading zeros, so the longer is the larger, else the digits decide.
  const std::string_view x = std::string_view(a).substr(a_negative ? 1 : 0);
  const std::string_view y = std::string_view(b).substr(b_negative ? 1 : 0);
  const int magnitude =
      x.size() != y.size() ? (x.size() < y.size() ? -1 : 1) : (x == y ? 0 : (x < y ? -1 : 1));
  return a_negative ? -magnitude : magnitude;
}

}  // namespace chordfit::cli
