#include "core/diagnostics.h"

#include <ostream>

namespace chordfit {

void Diagnostics::error(std::string file, std::string where, std::string what) {
  // Readers that look at one bad value for several fields report it once per field asked
  // ("tracings[0]: expected an object, got number" four times): one line says it.
  if (!reported_.emplace(file, where, what).second) return;
  problems_.push_back({std::move(file), std::move(where), std::move(what)});
}

void Diagnostics::merge(const Diagnostics& other) {
  for (const Problem& p : other.problems_) error(p.file, p.where, p.what);
}

void Diagnostics::print(std::ostream& out) const {
  for (const Problem& p : problems_) {
    out << "error: " << p.file << ": ";
    if (!p.where.empty()) out << p.where << ": ";  // a problem of the whole file names no field
    out << p.what << "\n";
  }
}

}  // namespace chordfit
