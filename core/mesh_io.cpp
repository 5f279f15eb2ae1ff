#include "core/mesh_io.h"
#include "core/quoted_text.h"
#include "core/text_case.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/cgal_backend.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;

bool isSpace(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

// A word from the file as it may appear in a message: a corrupt binary file can put any
// bytes where a keyword was expected (shownText escapes them).
std::string quotedWord(const std::string& word) { return "'" + shownText(word) + "'"; }

// ---------------------------------------------------------------------------------------
// Legacy VTK polydata reader.

// Thrown inside the parser only; readVtk turns it into a Diagnostics entry.
struct VtkError {
  std::string where;
  std::string what;
};

enum class CellKind { kPolygons, kStrips, kIgnored };

// The element types a legacy file may declare, with their binary size.
int vtkTypeSize(const std::string& type) {
  static const std::pair<const char*, int> kTypes[] = {
      {"unsigned_char", 1},  {"char", 1},          {"signed_char", 1},  {"unsigned_short", 2},
      {"short", 2},          {"unsigned_int", 4},  {"int", 4},          {"unsigned_long", 8},
      {"long", 8},           {"float", 4},         {"double", 8},       {"vtkidtype", 8},
      {"vtktypeint8", 1},    {"vtktypeuint8", 1},  {"vtktypeint16", 2}, {"vtktypeuint16", 2},
      {"vtktypeint32", 4},   {"vtktypeuint32", 4}, {"vtktypeint64", 8}, {"vtktypeuint64", 8},
      {"vtktypefloat32", 4}, {"vtktypefloat64", 8}};
  for (const auto& [name, size] : kTypes)
    if (type == name) return size;
  return 0;
}

bool isVtkFloatType(const std::string& type) {
  return type == "float" || type == "double" || type == "vtktypefloat32" ||
         type == "vtktypefloat64";
}

bool isVtkUnsignedType(const std::string& type) {
  return type.rfind("unsigned", 0) == 0 || type.rfind("vtktypeuint", 0) == 0;
}

class VtkParser {
 public:
  explicit VtkParser(const std::string& bytes) : bytes_(bytes) {}

  void parse(Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
    parseHeader();
    bool have_points = false;
    while (true) {
      const std::size_t keyword_pos = skipSpace();
      const std::string word = token();
      const std::string keyword = asciiLowercase(word);
      if (keyword.empty() || keyword == "point_data" || keyword == "cell_data") break;
      if (keyword == "dataset") {
        parseDataset(keyword_pos);
      } else if (keyword == "points") {
        requireDataset(keyword_pos, "POINTS");
        parsePoints(keyword_pos, V);
        have_points = true;
      } else if (keyword == "polygons") {
        requireDataset(keyword_pos, "POLYGONS");
        parseCells(keyword_pos, "POLYGONS", CellKind::kPolygons);
      } else if (keyword == "triangle_strips") {
        requireDataset(keyword_pos, "TRIANGLE_STRIPS");
        parseCells(keyword_pos, "TRIANGLE_STRIPS", CellKind::kStrips);
      } else if (keyword == "vertices" || keyword == "lines") {
        requireDataset(keyword_pos, "VERTICES/LINES");
        parseCells(keyword_pos, keyword == "lines" ? "LINES" : "VERTICES", CellKind::kIgnored);
      } else if (keyword == "field") {
        skipField(keyword_pos);
      } else if (keyword == "metadata") {
        skipMetadata();
      } else {
        fail(keyword_pos, "unexpected keyword " + quotedWord(word));
      }
    }
    if (!have_points) fail(pos_, "no POINTS section");
    if (triangles_.empty()) fail(pos_, "no POLYGONS or TRIANGLE_STRIPS with 3 or more corners");
    F.resize(static_cast<Eigen::Index>(triangles_.size()), 3);
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      for (int k = 0; k < 3; ++k) F(static_cast<Eigen::Index>(t), k) = triangles_[t][k];
  }

 private:
  // Line numbers mean nothing once binary data has been read, so from then on a byte offset
  // is reported instead.
  std::string location(std::size_t pos) const {
    if (binary_data_seen_) return "byte " + std::to_string(pos);
    const auto end = bytes_.begin() + static_cast<std::ptrdiff_t>(std::min(pos, bytes_.size()));
    return "line " + std::to_string(1 + std::count(bytes_.begin(), end, '\n'));
  }

  [[noreturn]] void fail(std::size_t pos, const std::string& what) const {
    throw VtkError{location(pos), what};
  }

  std::size_t remaining() const { return bytes_.size() - pos_; }

  std::size_t skipSpace() {
    while (pos_ < bytes_.size() && isSpace(bytes_[pos_])) ++pos_;
    return pos_;
  }

  std::string token() {
    skipSpace();
    const std::size_t begin = pos_;
    while (pos_ < bytes_.size() && !isSpace(bytes_[pos_])) ++pos_;
    return bytes_.substr(begin, pos_ - begin);
  }

  std::string peekToken() {
    const std::size_t saved = pos_;
    std::string t = token();
    pos_ = saved;
    return t;
  }

  std::string line() {
    const std::size_t begin = pos_;
    std::size_t eol = bytes_.find('\n', pos_);
    if (eol == std::string::npos) eol = bytes_.size();
    pos_ = std::min(bytes_.size(), eol + 1);
    std::string text = bytes_.substr(begin, eol - begin);
    if (!text.empty() && text.back() == '\r') text.pop_back();
    return text;
  }

  unsigned long long count(const std::string& what) {
    const std::size_t at = skipSpace();
    const std::string text = token();
    if (text.empty() || !std::isdigit(static_cast<unsigned char>(text[0])))
      fail(at, "expected " + what + ", got " + quotedWord(text));
    errno = 0;
    char* end = nullptr;
    const unsigned long long value = std::strtoull(text.c_str(), &end, 10);
    if (errno != 0 || *end != '\0') fail(at, "expected " + what + ", got " + quotedWord(text));
    return value;
  }

  void parseHeader() {
    const std::string first = line();
    const std::string magic = "# vtk DataFile Version";
    if (first.compare(0, magic.size(), magic) != 0)
      fail(0, "not a legacy VTK file (the first line is not '" + magic + " x.y')");
    line();  // title
    const std::size_t format_pos = pos_;
    std::string format = line();
    format.erase(std::remove_if(format.begin(), format.end(), isSpace), format.end());
    format = asciiLowercase(format);
    if (format == "binary") {
      binary_ = true;
    } else if (format != "ascii") {
      fail(format_pos, "expected ASCII or BINARY, got " + quotedWord(format));
    }
  }

  void parseDataset(std::size_t keyword_pos) {
    const std::string type = token();
    if (asciiLowercase(type) != "polydata")
      fail(keyword_pos,
           "unsupported dataset type " + quotedWord(type) + " (only POLYDATA can be read)");
    have_dataset_ = true;
  }

  void requireDataset(std::size_t keyword_pos, const std::string& section) const {
    if (!have_dataset_) fail(keyword_pos, section + " before DATASET POLYDATA");
  }

  std::string dataType(const std::string& section) {
    const std::size_t at = skipSpace();
    const std::string type = asciiLowercase(token());
    if (vtkTypeSize(type) == 0) fail(at, section + ": unsupported data type " + quotedWord(type));
    return type;
  }

  // Checks that `n` values can possibly follow, so that a corrupt count cannot make us
  // allocate more than the file could hold.
  void requireRoom(unsigned long long n, const std::string& type, const std::string& section) {
    const std::size_t at = pos_;
    if (binary_) {
      skipToNextLine();
      const auto size = static_cast<unsigned long long>(vtkTypeSize(type));
      if (n > remaining() / size)
        fail(at, section + ": " + std::to_string(n) + " values do not fit in the rest of the file");
    } else if (n > remaining() / 2 + 1) {  // a value and a separator take 2 bytes or more
      fail(at, section + ": " + std::to_string(n) + " values do not fit in the rest of the file");
    }
  }

  // Binary data starts right after the newline that ends the keyword line.
  void skipToNextLine() {
    const std::size_t eol = bytes_.find('\n', pos_);
    pos_ = eol == std::string::npos ? bytes_.size() : eol + 1;
  }

  std::uint64_t bigEndian(int size) {
    std::uint64_t value = 0;
    for (int i = 0; i < size; ++i)
      value = (value << 8) | static_cast<unsigned char>(bytes_[pos_ + static_cast<std::size_t>(i)]);
    pos_ += static_cast<std::size_t>(size);
    return value;
  }

  double binaryReal(const std::string& type) {
    const int size = vtkTypeSize(type);
    const std::uint64_t raw = bigEndian(size);
    if (isVtkFloatType(type)) {
      if (size == 4) {
        const auto bits = static_cast<std::uint32_t>(raw);
        float f;
        std::memcpy(&f, &bits, sizeof f);
        return f;
      }
      double d;
      std::memcpy(&d, &raw, sizeof d);
      return d;
    }
    return static_cast<double>(binaryInteger(raw, size, type));
  }

  static long long binaryInteger(std::uint64_t raw, int size, const std::string& type) {
    if (isVtkUnsignedType(type) || size == 8) return static_cast<long long>(raw);
    const std::uint64_t sign = std::uint64_t{1} << (8 * size - 1);
    return static_cast<long long>((raw ^ sign) - sign);  // sign-extend
  }

  // strtod also accepts "nan" and "inf": non-finite values are the mesh checks' business.
  double asciiReal() {
    const std::size_t at = skipSpace();
    if (at >= bytes_.size()) fail(at, "file ends inside a data array");
    char* end = nullptr;
    const double value = std::strtod(bytes_.c_str() + at, &end);
    const auto consumed = static_cast<std::size_t>(end - bytes_.c_str());
    if (consumed == at || (consumed < bytes_.size() && !isSpace(bytes_[consumed])))
      fail(at, quotedWord(peekToken()) + " is not a number");
    pos_ = consumed;
    return value;
  }

  long long asciiInteger() {
    const std::size_t at = skipSpace();
    if (at >= bytes_.size()) fail(at, "file ends inside a data array");
    char* end = nullptr;
    errno = 0;
    const long long value = std::strtoll(bytes_.c_str() + at, &end, 10);
    const auto consumed = static_cast<std::size_t>(end - bytes_.c_str());
    if (consumed == at || errno != 0 || (consumed < bytes_.size() && !isSpace(bytes_[consumed])))
      fail(at, quotedWord(peekToken()) + " is not an integer");
    pos_ = consumed;
    return value;
  }

  std::vector<long long> integers(unsigned long long n, const std::string& type,
                                  const std::string& section) {
    if (isVtkFloatType(type)) fail(pos_, section + ": expected an integer type, got " + type);
    requireRoom(n, type, section);
    std::vector<long long> values(static_cast<std::size_t>(n));
    const int size = vtkTypeSize(type);
    for (long long& v : values)
      v = binary_ ? binaryInteger(bigEndian(size), size, type) : asciiInteger();
    binary_data_seen_ = binary_data_seen_ || binary_;
    return values;
  }

  void skipValues(unsigned long long n, const std::string& type, const std::string& section) {
    requireRoom(n, type, section);
    if (binary_) {
      pos_ += static_cast<std::size_t>(n) * static_cast<std::size_t>(vtkTypeSize(type));
      binary_data_seen_ = true;
      return;
    }
    for (unsigned long long i = 0; i < n; ++i) asciiReal();
  }

  void parsePoints(std::size_t keyword_pos, Eigen::MatrixXd& V) {
    const unsigned long long n = count("a point count");
    const std::string type = dataType("POINTS");
    if (n > std::numeric_limits<unsigned long long>::max() / 3)
      fail(keyword_pos, "too many points");
    requireRoom(3 * n, type, "POINTS");
    V.resize(static_cast<Eigen::Index>(n), 3);
    for (Eigen::Index i = 0; i < V.rows(); ++i)
      for (int k = 0; k < 3; ++k) V(i, k) = binary_ ? binaryReal(type) : asciiReal();
    binary_data_seen_ = binary_data_seen_ || binary_;
  }

  // Classic layout: "<KIND> n size" followed by n count-prefixed index lists.
  // VTK >= 9 (file version 5.x): "<KIND> offsets_count connectivity_size" followed by
  // "OFFSETS type" and "CONNECTIVITY type" arrays.
  void parseCells(std::size_t keyword_pos, const std::string& section, CellKind kind) {
    const unsigned long long n = count("a cell count");
    const unsigned long long size = count("a connectivity size");
    std::vector<std::vector<long long>> cells;
    if (asciiLowercase(peekToken()) == "offsets") {
      cells = offsetCells(keyword_pos, section, n, size);
    } else {
      cells = classicCells(keyword_pos, section, n, size);
    }
    if (kind == CellKind::kIgnored) return;
    for (const auto& cell : cells) {
      if (kind == CellKind::kPolygons) {
        addPolygon(keyword_pos, cell);
      } else {
        addStrip(keyword_pos, cell);
      }
    }
  }

  std::vector<std::vector<long long>> classicCells(std::size_t keyword_pos,
                                                   const std::string& section, unsigned long long n,
                                                   unsigned long long size) {
    const std::vector<long long> data = integers(size, binary_ ? "int" : "vtktypeint64", section);
    if (n > data.size()) fail(keyword_pos, section + ": more cells than connectivity entries");
    std::vector<std::vector<long long>> cells(static_cast<std::size_t>(n));
    std::size_t at = 0;
    for (auto& cell : cells) {
      const long long corners = at < data.size() ? data[at] : -1;
      if (corners < 0 || static_cast<unsigned long long>(corners) > data.size() - at - 1)
        fail(keyword_pos,
             section + ": cell list does not match the declared size " + std::to_string(size));
      cell.assign(data.begin() + static_cast<std::ptrdiff_t>(at + 1),
                  data.begin() + static_cast<std::ptrdiff_t>(at + 1 + corners));
      at += 1 + static_cast<std::size_t>(corners);
    }
    if (at != data.size())
      fail(keyword_pos, section + ": declared size " + std::to_string(size) + " but the " +
                            std::to_string(n) + " cells use " + std::to_string(at) + " entries");
    return cells;
  }

  std::vector<long long> namedArray(const std::string& name, unsigned long long n,
                                    const std::string& section) {
    const std::size_t at = skipSpace();
    if (asciiLowercase(token()) != name) fail(at, section + ": expected " + asciiLowercase(name));
    const std::string type = dataType(section);
    return integers(n, type, section);
  }

  std::vector<std::vector<long long>> offsetCells(std::size_t keyword_pos,
                                                  const std::string& section, unsigned long long n,
                                                  unsigned long long size) {
    const std::vector<long long> offsets = namedArray("offsets", n, section + " OFFSETS");
    const std::vector<long long> connectivity =
        namedArray("connectivity", size, section + " CONNECTIVITY");
    if (offsets.empty()) return {};
    if (offsets.front() != 0 || offsets.back() != static_cast<long long>(size))
      fail(keyword_pos,
           section + ": offsets must run from 0 to the connectivity size " + std::to_string(size));
    for (std::size_t c = 0; c + 1 < offsets.size(); ++c) {
      if (offsets[c + 1] < offsets[c])
        fail(keyword_pos, section + ": offsets decrease at cell " + std::to_string(c));
    }
    // Monotone from 0 to size: every range below lies inside `connectivity`.
    std::vector<std::vector<long long>> cells(offsets.size() - 1);
    for (std::size_t c = 0; c + 1 < offsets.size(); ++c)
      cells[c].assign(connectivity.begin() + offsets[c], connectivity.begin() + offsets[c + 1]);
    return cells;
  }

  int toIndex(std::size_t keyword_pos, long long value) const {
    if (value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max())
      fail(keyword_pos, "vertex index " + std::to_string(value) + " is out of range");
    return static_cast<int>(value);
  }

  // Fan triangulation. A polygon with fewer than 3 corners is an error, as in the other
  // formats: dropped, it would leave a hole in the leaflet without a word.
  void addPolygon(std::size_t keyword_pos, const std::vector<long long>& cell) {
    if (cell.size() < 3)
      fail(keyword_pos, "POLYGONS: a polygon with " + std::to_string(cell.size()) +
                            " corner(s); a face needs at least 3");
    for (std::size_t k = 1; k + 1 < cell.size(); ++k)
      triangles_.push_back({toIndex(keyword_pos, cell[0]), toIndex(keyword_pos, cell[k]),
                            toIndex(keyword_pos, cell[k + 1])});
  }

  // Every other strip triangle is flipped to keep one orientation. Triangles that repeat
  // an index are the strip's own turn-around trick, not geometry, so they are dropped.
  void addStrip(std::size_t keyword_pos, const std::vector<long long>& cell) {
    for (std::size_t k = 0; k + 2 < cell.size(); ++k) {
      std::array<int, 3> t{toIndex(keyword_pos, cell[k]), toIndex(keyword_pos, cell[k + 1]),
                           toIndex(keyword_pos, cell[k + 2])};
      if (k % 2 == 1) std::swap(t[0], t[1]);
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
      triangles_.push_back(t);
    }
  }

  // "FIELD name n" then n arrays "name components tuples type" + data (+ METADATA).
  void skipField(std::size_t keyword_pos) {
    token();  // field name
    const unsigned long long arrays = count("an array count");
    for (unsigned long long a = 0; a < arrays; ++a) {
      if (asciiLowercase(peekToken()) == "metadata") {
        token();
        skipMetadata();
      }
      const std::string name = token();
      if (name.empty()) fail(keyword_pos, "FIELD: file ends inside the field data");
      if (name == "NULL_ARRAY") continue;
      const unsigned long long components = count("a component count");
      const unsigned long long tuples = count("a tuple count");
      const std::size_t type_pos = skipSpace();
      const std::string type = asciiLowercase(token());
      if (vtkTypeSize(type) == 0)
        fail(type_pos,
             "FIELD array " + quotedWord(name) + ": cannot skip data of type " + quotedWord(type));
      if (tuples != 0 && components > std::numeric_limits<unsigned long long>::max() / tuples)
        fail(keyword_pos, "FIELD array " + quotedWord(name) + " is too large");
      skipValues(components * tuples, type, "FIELD array " + quotedWord(name));
    }
  }

  // A METADATA block (VTK >= 8) ends with an empty line.
  void skipMetadata() {
    line();  // rest of the METADATA line
    while (pos_ < bytes_.size()) {
      std::string text = line();
      if (std::all_of(text.begin(), text.end(), isSpace)) break;
    }
  }

  const std::string& bytes_;
  std::size_t pos_ = 0;
  bool binary_ = false;
  bool binary_data_seen_ = false;
  bool have_dataset_ = false;
  std::vector<std::array<int, 3>> triangles_;
};

bool readVtk(const fs::path& path, const std::string& file, Eigen::MatrixXd& V, Eigen::MatrixXi& F,
             Diagnostics& diagnostics) {
  std::string bytes;
  if (!readWholeFile(path, bytes)) {
    diagnostics.error(file, "", cannotBeRead(path));
    return false;
  }
  try {
    VtkParser(bytes).parse(V, F);
    return true;
  } catch (const VtkError& e) {
    diagnostics.error(file, e.where, e.what);
  } catch (const std::exception& e) {  // e.g. std::bad_alloc on a giant but plausible count
    diagnostics.error(file, "", std::string("cannot be read: ") + e.what());
  }
  return false;
}

// cgalReadTriangleSoup's message may start with a location ("line 7: ...", "byte 880: ...",
// "element face 3: ...", "facet 12: ...", "face 5: ...", "header: ..."); it belongs in
// Problem::where.
void reportSoupError(const std::string& file, const std::string& error, Diagnostics& diagnostics) {
  const std::size_t colon = error.find(": ");
  if (colon != std::string::npos) {
    const std::string prefix = error.substr(0, colon);
    for (const char* start : {"line ", "byte ", "element ", "facet ", "face ", "header"}) {
      if (prefix.rfind(start, 0) == 0) {
        diagnostics.error(file, prefix, error.substr(colon + 2));
        return;
      }
    }
  }
  diagnostics.error(file, "", error);
}

// ---------------------------------------------------------------------------------------
// Writers.

void requireExtension(const fs::path& path, const std::string& extension) {
  if (asciiLowercase(path.extension().string()) != extension)
    throw std::runtime_error(path.string() + ": expected a " + extension + " file name");
}

void requireShapes(const fs::path& path, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                   const std::vector<VertexScalarField>& scalars) {
  if (V.cols() != 3 || (F.cols() != 3 && F.rows() != 0))
    throw std::invalid_argument(path.string() + ": V and F must have 3 columns");
  for (const VertexScalarField& s : scalars) {
    if (s.values.size() != V.rows())
      throw std::invalid_argument(path.string() + ": scalar field '" + s.name + "' has " +
                                  std::to_string(s.values.size()) + " values for " +
                                  std::to_string(V.rows()) + " vertices");
  }
}

// PLY and VTK names are single words.
std::string sanitizedName(const std::string& name, std::size_t index) {
  if (name.empty()) return "scalar_" + std::to_string(index);
  std::string out = name;
  for (char& c : out)
    if (isSpace(c)) c = '_';
  return out;
}

// The bytes of a 4- or 8-byte number in the given order: binary PLY is little-endian,
// binary legacy VTK big-endian (VTK file formats, "Binary Files").
enum class ByteOrder { kLittle, kBig };

template <typename T>
void appendBinary(std::string& out, T value, ByteOrder order) {
  static_assert(sizeof(T) == 4 || sizeof(T) == 8);
  std::uint64_t bits = 0;
  if constexpr (sizeof(T) == 8) {
    std::memcpy(&bits, &value, sizeof value);
  } else {
    std::uint32_t narrow;
    std::memcpy(&narrow, &value, sizeof value);
    bits = narrow;
  }
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    const std::size_t byte = order == ByteOrder::kLittle ? i : sizeof(T) - 1 - i;
    out += static_cast<char>((bits >> (8 * byte)) & 0xff);
  }
}

}  // namespace

bool readMesh(const fs::path& path, Eigen::MatrixXd& V, Eigen::MatrixXi& F,
              Diagnostics& diagnostics, const std::string& display_name) {
  const std::string file = display_name.empty() ? path.string() : display_name;
  V.resize(0, 3);
  F.resize(0, 3);
  if (const std::string problem = inputFileProblem(path, "a mesh file"); !problem.empty()) {
    diagnostics.error(file, "", problem);
    return false;
  }
  const std::string extension = asciiLowercase(path.extension().string());
  // The mesh formats start with a keyword or numbers: a byte-order mark read as "first line
  // is not 'ply'" or CGAL's bare "could not parse", the mark itself invisible. (A binary
  // STL's 80-byte header may hold any bytes.)
  if (extension != ".stl" && startsWithByteOrderMark(path)) {
    diagnostics.error(file, "",
                      "starts with a UTF-8 byte-order mark (bytes EF BB BF), which mesh files "
                      "must not have: save it without one");
    return false;
  }
  bool ok = false;
  if (extension == ".vtk") {
    ok = readVtk(path, file, V, F, diagnostics);
  } else if (extension == ".ply" || extension == ".obj" || extension == ".stl" ||
             extension == ".off") {
    std::string error;
    ok = cgalReadTriangleSoup(path, V, F, error);
    if (!ok) reportSoupError(file, error, diagnostics);
  } else {
    diagnostics.error(file, "",
                      "unsupported mesh format '" + path.extension().string() +
                          "' (expected .ply, .obj, .stl, .off or .vtk)");
  }
  if (!ok) {
    V.resize(0, 3);
    F.resize(0, 3);
  }
  return ok;
}

// Also throws std::invalid_argument when V or F is not #-by-3 or a scalar field's length is
// not #V.
void writePly(const fs::path& path, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
              const std::vector<VertexScalarField>& scalars) {
  requireExtension(path, ".ply");
  requireShapes(path, V, F, scalars);
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by chordfit\n";
  out += "element vertex " + std::to_string(V.rows()) + "\n";
  out += "property double x\nproperty double y\nproperty double z\n";
  for (std::size_t s = 0; s < scalars.size(); ++s)
    out += "property float " + sanitizedName(scalars[s].name, s) + "\n";
  out += "element face " + std::to_string(F.rows()) + "\n";
  out += "property list uchar int vertex_indices\nend_header\n";
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    for (int k = 0; k < 3; ++k) appendBinary(out, V(i, k), ByteOrder::kLittle);
    for (const VertexScalarField& s : scalars)
      appendBinary(out, static_cast<float>(s.values(i)), ByteOrder::kLittle);
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    out += static_cast<char>(3);
    for (int k = 0; k < 3; ++k)
      appendBinary(out, static_cast<std::int32_t>(F(f, k)), ByteOrder::kLittle);
  }
  writeFileAtomically(path, out);
}

// Also throws std::invalid_argument like writePly. Binary legacy VTK: the scalars hold NaN
// (distance_to_tracing_mm away from the tracing planes), and VTK 9.1's ASCII legacy reader
// (Debian bookworm's ParaView and python3-vtk9) cannot parse "nan": it misread every value
// after the first one, silently. Binary floats carry NaN as NaN.
void writeVtk(const fs::path& path, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
              const std::vector<VertexScalarField>& scalars) {
  requireExtension(path, ".vtk");
  requireShapes(path, V, F, scalars);
  std::string out = "# vtk DataFile Version 3.0\nchordfit mesh\nBINARY\nDATASET POLYDATA\n";
  out += "POINTS " + std::to_string(V.rows()) + " double\n";
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    for (int k = 0; k < 3; ++k) appendBinary(out, V(i, k), ByteOrder::kBig);
  out += "\nPOLYGONS " + std::to_string(F.rows()) + " " + std::to_string(4 * F.rows()) + "\n";
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    appendBinary(out, std::int32_t{3}, ByteOrder::kBig);
    for (int k = 0; k < 3; ++k)
      appendBinary(out, static_cast<std::int32_t>(F(f, k)), ByteOrder::kBig);
  }
  out += "\n";
  if (!scalars.empty()) out += "POINT_DATA " + std::to_string(V.rows()) + "\n";
  for (std::size_t s = 0; s < scalars.size(); ++s) {
    out += "SCALARS " + sanitizedName(scalars[s].name, s) + " float 1\nLOOKUP_TABLE default\n";
    for (Eigen::Index i = 0; i < V.rows(); ++i)
      appendBinary(out, static_cast<float>(scalars[s].values(i)), ByteOrder::kBig);
    out += "\n";
  }
  writeFileAtomically(path, out);
}

}  // namespace chordfit
