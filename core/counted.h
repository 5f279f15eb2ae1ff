// A count and its noun in the right number, for messages and reports: "1 thread", "2 threads",
// "1 vertex", "3 vertices". Counts that are often 1 (one thread, one tip, one cord scaled)
// read "1 threads" when the noun was written plural.
#pragma once

#include <string>

namespace chordfit {

// `one` for a count of 1, else `many` (default: `one` + "s"). For a count printed on its own,
// e.g. in a printf field of fixed width.
inline std::string nounFor(long long count, const std::string& one, const std::string& many = "") {
  if (count == 1) return one;
  return many.empty() ? one + "s" : many;
}

// "<count> <noun>", the noun as nounFor gives it.
inline std::string counted(long long count, const std::string& one, const std::string& many = "") {
  return std::to_string(count) + " " + nounFor(count, one, many);
}

}  // namespace chordfit
