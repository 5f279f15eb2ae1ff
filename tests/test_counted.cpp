// The count-and-noun helper of the messages (core/counted.h).
#include <cstddef>

#include <gtest/gtest.h>

#include "core/counted.h"

namespace chordfit {
namespace {

TEST(Counted, PutsTheNounInTheNumberOfItsCount) {
  EXPECT_EQ(counted(1, "thread"), "1 thread");
  EXPECT_EQ(counted(2, "thread"), "2 threads");
  EXPECT_EQ(counted(0, "cord"), "0 cords");
  EXPECT_EQ(counted(1, "vertex", "vertices"), "1 vertex");
  EXPECT_EQ(counted(596, "vertex", "vertices"), "596 vertices");
  EXPECT_EQ(counted(std::size_t{1}, "PM tip"), "1 PM tip");
  EXPECT_EQ(nounFor(1, "cord"), "cord");
  EXPECT_EQ(nounFor(27, "cord"), "cords");
}

}  // namespace
}  // namespace chordfit
