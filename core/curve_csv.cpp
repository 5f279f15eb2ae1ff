#include "core/curve_csv.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/atomic_file.h"
#include "core/decimal_number.h"
#include "core/quoted_text.h"
#include "core/text_case.h"

namespace chordfit {
namespace {

// Bad lines reported per file before giving up on it.
constexpr int kMaxReportedLines = 5;

// Fields of a data line: split at commas, else semicolons, else runs of blanks.
std::vector<std::string> splitFields(const std::string& line) {
  std::vector<std::string> fields;
  const char separator = line.find(',') != std::string::npos   ? ','
                         : line.find(';') != std::string::npos ? ';'
                                                               : '\0';
  if (separator != '\0') {
    std::istringstream in(line);
    for (std::string field; std::getline(in, field, separator);) fields.push_back(trimmed(field));
    if (!line.empty() && line.back() == separator) fields.push_back("");
  } else {
    std::istringstream in(line);
    for (std::string field; in >> field;) fields.push_back(field);
  }
  return fields;
}

// The value of a "# key = value" header line of an .fcsv file, or "" when `line` is not it.
std::string headerValue(const std::string& line, const std::string& key) {
  const std::string body = trimmed(line.substr(1));
  if (asciiLowercase(body.substr(0, key.size())) != asciiLowercase(key)) return "";
  const auto eq = body.find('=', key.size());
  return eq == std::string::npos ? "" : trimmed(body.substr(eq + 1));
}

// Column layout of the coordinates: the three field indices and whether they are RAS.
struct Columns {
  std::array<int, 3> index{0, 1, 2};
  bool ras = false;
};

// Coordinate columns named by a header row (x,y,z | l,p,s | r,a,s); false when it names none.
bool columnsFromNames(const std::vector<std::string>& names, Columns& columns) {
  static const std::array<std::array<const char*, 3>, 3> kTriples = {
      {{"x", "y", "z"}, {"l", "p", "s"}, {"r", "a", "s"}}};
  for (std::size_t t = 0; t < kTriples.size(); ++t) {
    Columns found;
    bool complete = true;
    for (int k = 0; k < 3 && complete; ++k) {
      const auto it = std::find_if(names.begin(), names.end(), [&](const std::string& n) {
        return asciiLowercase(n) == kTriples[t][k];
      });
      complete = it != names.end();
      if (complete) found.index[k] = static_cast<int>(it - names.begin());
    }
    if (complete) {
      found.ras = t == 2;
      columns = found;
      return true;
    }
  }
  return false;
}

class CurveTextReader {
 public:
  CurveTextReader(const std::string& file, Diagnostics& diagnostics, bool fcsv)
      : file_(file), diagnostics_(diagnostics), fcsv_(fcsv) {
    columns_.index = fcsv ? std::array<int, 3>{1, 2, 3} : std::array<int, 3>{0, 1, 2};
    columns_.ras = fcsv;  // .fcsv without a CoordinateSystem line predates LPS files
  }

  // Returns false once the file is hopeless (too many bad lines).
  bool line(const std::string& raw, int number) {
    const std::string text = trimmed(raw);
    if (text.empty()) return true;
    if (text[0] == '#') return fcsv_ ? header(text, number) : true;
    const std::vector<std::string> fields = splitFields(text);
    if (!fcsv_ && !seen_data_ && !seen_header_) {
      double probe = 0.0;
      if (!fields.empty() && !parseDecimal(fields[0], probe)) {
        seen_header_ = true;
        if (!columnsFromNames(fields, columns_)) {
          return bad(number,
                     "the header names no coordinate columns (expected x,y,z, l,p,s or "
                     "r,a,s), got " +
                         quotedText(text));
        }
        return true;
      }
    }
    seen_data_ = true;
    const int needed = *std::max_element(columns_.index.begin(), columns_.index.end()) + 1;
    if (static_cast<int>(fields.size()) < needed) {
      return bad(number, "expected at least " + std::to_string(needed) + " fields, got " +
                             std::to_string(fields.size()));
    }
    std::array<double, 3> p{};
    static const char* kAxis[] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      const std::string& field = fields[columns_.index[k]];
      if (!parseDecimal(field, p[k])) {
        return bad(number,
                   std::string(kAxis[k]) + " is not a finite decimal number: " + quotedText(field));
      }
    }
    points_.push_back(p);
    lines_.push_back(number);
    return true;
  }

  bool finish(Curve& curve) {
    if (bad_lines_ > 0) return false;
    if (points_.empty()) {
      diagnostics_.error(file_, "", "no points");
      return false;
    }
    curve.closed = false;
    curve.read_as_ras = columns_.ras;
    const char* other = columns_.ras ? "LPS" : "RAS";
    curve.other_frame_syntax =
        fcsv_ ? std::string("say \"# CoordinateSystem = ") + other + "\" in the file's header" +
                    (columns_.ras && !system_line_ ? " (an .fcsv without that line is read as RAS)"
                                                   : "")
              : std::string("name the columns ") + (columns_.ras ? "l,p,s" : "r,a,s") +
                    " in a header row";
    curve.points.resize(static_cast<Eigen::Index>(points_.size()), 3);
    const double flip = columns_.ras ? -1.0 : 1.0;  // RAS -> LPS: negate R and A
    for (std::size_t i = 0; i < points_.size(); ++i) {
      const auto r = static_cast<Eigen::Index>(i);
      curve.points(r, 0) = flip * points_[i][0];
      curve.points(r, 1) = flip * points_[i][1];
      curve.points(r, 2) = points_[i][2];
      curve.point_wheres.push_back("line " + std::to_string(lines_[i]));
    }
    return true;
  }

 private:
  bool header(const std::string& text, int number) {
    if (const std::string system = headerValue(text, "CoordinateSystem"); !system.empty()) {
      system_line_ = true;
      if (system == "RAS" || system == "0") {
        columns_.ras = true;
      } else if (system == "LPS" || system == "1") {
        columns_.ras = false;
      } else {
        return bad(number,
                   "CoordinateSystem: expected LPS, RAS, 0 or 1, got " + quotedText(system));
      }
    } else if (const std::string names = headerValue(text, "columns"); !names.empty()) {
      const bool ras = columns_.ras;
      if (!columnsFromNames(splitFields(names), columns_)) {
        return bad(number, "columns: expected x, y and z among " + quotedText(names));
      }
      columns_.ras = ras;  // the coordinate system comes from its own line
    }
    return true;
  }

  bool bad(int number, const std::string& what) {
    diagnostics_.error(file_, "line " + std::to_string(number), what);
    return ++bad_lines_ < kMaxReportedLines;
  }

  std::string file_;
  Diagnostics& diagnostics_;
  bool fcsv_ = false;
  bool system_line_ = false;  // a "# CoordinateSystem" line was read
  Columns columns_;
  bool seen_header_ = false, seen_data_ = false;
  int bad_lines_ = 0;
  std::vector<std::array<double, 3>> points_;
  std::vector<int> lines_;  // the line of each point, for point_wheres
};

}  // namespace

bool isDelimitedCurveFile(const std::filesystem::path& path) {
  const std::string extension = asciiLowercase(path.extension().string());
  return extension == ".fcsv" || extension == ".csv" || extension == ".txt";
}

bool readDelimitedCurve(const std::filesystem::path& path, const std::string& file, Curve& curve,
                        Diagnostics& diagnostics) {
  try {
    if (const std::string problem = inputFileProblem(path, "a curve file"); !problem.empty()) {
      diagnostics.error(file, "", problem);
      return false;
    }
    std::ifstream in(path);
    if (!in) {
      diagnostics.error(file, "", cannotBeRead(path));
      return false;
    }
    CurveTextReader reader(file, diagnostics, asciiLowercase(path.extension().string()) == ".fcsv");
    int number = 0;
    for (std::string line; std::getline(in, line);) {
      // A UTF-8 byte-order mark (spreadsheet exports write one) is not part of the header.
      if (number == 0 && line.rfind(kUtf8ByteOrderMark, 0) == 0) line.erase(0, 3);
      if (!reader.line(line, ++number)) break;
    }
    Curve result;
    if (!reader.finish(result)) return false;
    curve = std::move(result);
    return true;
  } catch (const std::exception& e) {  // e.g. std::bad_alloc; the contract is "never throws"
    diagnostics.error(file, "", std::string("cannot be read: ") + e.what());
  }
  return false;
}

}  // namespace chordfit
