// Integer option values in any decimal form, always base 10 (tools/integer_text.h).
#include <gtest/gtest.h>

#include <string>

#include "tools/integer_text.h"

namespace chordfit::cli {
namespace {

TEST(CanonicalInteger, ReadsEveryDecimalFormOfAWholeNumber) {
  EXPECT_EQ(canonicalInteger("400"), "400");
  EXPECT_EQ(canonicalInteger("1e3"), "1000");
  EXPECT_EQ(canonicalInteger("1E+3"), "1000");
  EXPECT_EQ(canonicalInteger("400.0"), "400");
  EXPECT_EQ(canonicalInteger("2.50e1"), "25");
  EXPECT_EQ(canonicalInteger("+3"), "3");
  EXPECT_EQ(canonicalInteger(" 3 "), "3");
  EXPECT_EQ(canonicalInteger("-12"), "-12");
  EXPECT_EQ(canonicalInteger("-0"), "0");
  EXPECT_EQ(canonicalInteger("0.000"), "0");
  EXPECT_EQ(canonicalInteger("12000e-3"), "12");
}

// "077" is 77, not octal 63, and "08" is 8, not a malformed octal number.
TEST(CanonicalInteger, IsAlwaysBaseTen) {
  EXPECT_EQ(canonicalInteger("077"), "77");
  EXPECT_EQ(canonicalInteger("08"), "8");
  EXPECT_EQ(canonicalInteger("0100"), "100");
  EXPECT_EQ(canonicalInteger("0x40"), std::nullopt);
}

TEST(CanonicalInteger, RefusesWhatIsNotAWholeNumber) {
  for (const char* text : {"2.5", "1e-1", "abc", "", "+", ".", "1e", "1e+", "3 4", "1.5e0", "--3"})
    EXPECT_EQ(canonicalInteger(text), std::nullopt) << text;
}

// No rounding through a double: a digit beyond 2^53 stays, a fraction far down still counts.
TEST(CanonicalInteger, KeepsEveryDigit) {
  EXPECT_EQ(canonicalInteger("9007199254740993.0"), "9007199254740993");
  EXPECT_EQ(canonicalInteger("1e19"), "10000000000000000000");
  EXPECT_EQ(canonicalInteger("35.99999999999999999"), std::nullopt);
  EXPECT_EQ(canonicalInteger("18446744073709551615"), "18446744073709551615");
}

// A huge exponent gives a long text (refused as out of range later), not a billion digits.
TEST(CanonicalInteger, KeepsHugeExponentsShort) {
  const std::optional<std::string> huge = canonicalInteger("1e999999999");
  ASSERT_TRUE(huge.has_value());
  EXPECT_GT(huge->size(), 100u);
  EXPECT_LT(huge->size(), 200u);
  EXPECT_EQ(canonicalInteger("0e999999999"), "0");
  EXPECT_EQ(canonicalInteger("5e-999999999"), std::nullopt);
}

}  // namespace
}  // namespace chordfit::cli
