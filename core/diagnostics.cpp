#include "core/diagnostics.h"

#include <ostream>

namespace chordfit {

void Diagnostics::error(std::string file, std::string where, std::string what) {
  problems_.push_back({std::move(file), std::move(where), std::move(what)});
}

void Diagnostics::merge(const Diagnostics& other) {
  problems_.insert(problems_.end(), other.problems_.begin(), other.problems_.end());
}

void Diagnostics::print(std::ostream& out) const {
  for (const Problem& p : problems_) {
    out << "error: " << p.file << ": ";
    if (!p.where.empty()) out << p.where << ": ";  // a problem of the whole file names no field
    out << p.what << "\n";
  }
}

}  // namespace chordfit
