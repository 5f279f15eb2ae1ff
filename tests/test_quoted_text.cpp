// shownText / quotedText: a value from an input file as an error message quotes it.
#include <string>

#include <gtest/gtest.h>

#include "core/quoted_text.h"

namespace chordfit {
namespace {

TEST(QuotedText, KeepsPrintableTextAndUtf8AsItIs) {
  EXPECT_EQ(quotedText("12.5"), "\"12.5\"");
  EXPECT_EQ(quotedText("37 °C, é"), "\"37 °C, é\"");
  EXPECT_EQ(quotedText(""), "\"\"");
}

TEST(QuotedText, EscapesControlCharactersAndBytesThatAreNotUtf8) {
  EXPECT_EQ(shownText(std::string("a\0b", 3)), "a\\x00b");
  EXPECT_EQ(shownText("two\nlines\t\x1b[31m\x7f"), "two\\x0alines\\x09\\x1b[31m\\x7f");
  // A stray continuation byte, a lead byte without its continuation, an overlong '/', a
  // surrogate, a C1 control (U+0085) written in UTF-8.
  EXPECT_EQ(shownText("\x80"), "\\x80");
  EXPECT_EQ(shownText("\xc3("), "\\xc3(");
  EXPECT_EQ(shownText("\xc0\xaf"), "\\xc0\\xaf");
  EXPECT_EQ(shownText("\xed\xa0\x80"), "\\xed\\xa0\\x80");
  EXPECT_EQ(shownText("\xc2\x85"), "\\xc2\\x85");
}

TEST(QuotedText, CutsALongValueAfterItsCharactersWithAnEllipsis) {
  const std::string forty(kMaxQuotedCharacters, 'x');
  EXPECT_EQ(shownText(forty), forty);
  EXPECT_EQ(shownText(forty + "yz"), forty + "…");
  // Counted in characters: an escaped byte and a UTF-8 character are one each.
  EXPECT_EQ(shownText(std::string("\x01°abc"), 2), "\\x01°…");
  // A file name is shown whole.
  const std::string path = "/data/valves/" + std::string(60, 'd') + "/t.csv";
  EXPECT_EQ(quotedText(path, std::string::npos), "\"" + path + "\"");
}

}  // namespace
}  // namespace chordfit
