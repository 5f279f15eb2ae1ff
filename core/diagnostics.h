// Collects input problems so that one run reports all of them, each as
//   error: <file>: <field or line>: <problem>
// Readers add to a Diagnostics instead of throwing, so bad input never aborts.
#pragma once

#include <iosfwd>
#include <set>
#include <string>
#include <tuple>
#include <vector>

namespace chordfit {

struct Problem {
  std::string file;   // path as given by the user (or a file name inside a case)
  std::string where;  // field ("mesh", "tracings[2].points"), location ("line 7"), or empty
  std::string what;   // the problem, in words
};

class Diagnostics {
 public:
  // Adds a problem; one already collected word for word is not added again.
  void error(std::string file, std::string where, std::string what);
  bool ok() const { return problems_.empty(); }
  const std::vector<Problem>& problems() const { return problems_; }
  // Appends another collector's problems (used when a sub-reader worked on its own).
  void merge(const Diagnostics& other);
  // Prints one "error: file: where: what" line per problem ("error: file: what" without where).
  void print(std::ostream& out) const;

 private:
  std::vector<Problem> problems_;
  std::set<std::tuple<std::string, std::string, std::string>> reported_;  // file, where, what
};

// Thrown by the command-line layer for a fatal input problem already described in words.
struct InputError {
  Diagnostics diagnostics;
};

}  // namespace chordfit
