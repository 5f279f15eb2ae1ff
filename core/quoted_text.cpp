#include "core/quoted_text.h"

#include <cstdio>

namespace chordfit {
namespace {

// The length of the well-formed UTF-8 sequence starting at text[at] (1 for ASCII), or 0 when
// the bytes there are not one (a stray continuation byte, a truncated or overlong sequence, a
// surrogate, a code point beyond U+10FFFF). `code_point` gets its value.
std::size_t utf8SequenceLength(const std::string& text, std::size_t at, unsigned& code_point) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[at + k]); };
  const unsigned lead = byte(0);
  std::size_t length = 0;
  unsigned lowest = 0;  // the smallest code point a sequence of this length may carry
  if (lead < 0x80) {
    code_point = lead;
    return 1;
  } else if (lead >= 0xC2 && lead <= 0xDF) {
    length = 2, code_point = lead & 0x1F, lowest = 0x80;
  } else if (lead >= 0xE0 && lead <= 0xEF) {
    length = 3, code_point = lead & 0x0F, lowest = 0x800;
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    length = 4, code_point = lead & 0x07, lowest = 0x10000;
  } else {
    return 0;
  }
  if (at + length > text.size()) return 0;
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(k) & 0xC0) != 0x80) return 0;
    code_point = (code_point << 6) | (byte(k) & 0x3F);
  }
  const bool surrogate = code_point >= 0xD800 && code_point <= 0xDFFF;
  if (code_point < lowest || surrogate || code_point > 0x10FFFF) return 0;
  return length;
}

// C0 controls, DEL and the C1 controls (U+0080-U+009F): a terminal acts on them.
bool isControl(unsigned code_point) {
  return code_point < 0x20 || (code_point >= 0x7F && code_point <= 0x9F);
}

std::string escapedBytes(const std::string& text, std::size_t at, std::size_t length) {
  std::string escaped;
  for (std::size_t k = 0; k < length; ++k) {
    char hex[5];
    std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned char>(text[at + k]));
    escaped += hex;
  }
  return escaped;
}

}  // namespace

std::string shownText(const std::string& text, std::size_t max_characters) {
  std::string shown;
  std::size_t characters = 0;
  std::size_t at = 0;
  while (at < text.size()) {
    if (characters == max_characters) return shown + "…";
    unsigned code_point = 0;
    const std::size_t length = utf8SequenceLength(text, at, code_point);
    if (length == 0) {
      shown += escapedBytes(text, at, 1);
      at += 1;
    } else {
      shown += isControl(code_point) ? escapedBytes(text, at, length) : text.substr(at, length);
      at += length;
    }
    ++characters;
  }
  return shown;
}

std::string quotedText(const std::string& text, std::size_t max_characters) {
  return "\"" + shownText(text, max_characters) + "\"";
}

}  // namespace chordfit
