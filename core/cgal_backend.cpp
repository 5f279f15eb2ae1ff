// The only translation unit that includes CGAL (see cgal_backend.h for why).
//
// CGAL's polygon-soup readers trust their input more than a command-line tool can: a PLY
// "property" line before any "element" line indexes an empty vector, a non-float "x"
// property is dereferenced through a null pointer, and a corrupt list length or element
// count is passed straight to std::vector::resize. The pre-checks below reject such files
// with a located message before CGAL sees them.
#include "core/cgal_backend.h"
#include "core/counted.h"
#include "core/quoted_text.h"
#include "core/text_case.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/IO/STL.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>

#include "core/atomic_file.h"

namespace chordfit {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;

using DoubleKernel = CGAL::Simple_cartesian<double>;
using DoublePoint = DoubleKernel::Point_3;
using Polygon = std::vector<std::size_t>;

// ---------------------------------------------------------------------------------------
// Small text helpers shared by the pre-checks.

// A word from the file as it may appear in a message (a corrupt file can hold any bytes;
// shownText escapes them).
std::string quotedWord(const std::string& word) { return "'" + shownText(word) + "'"; }

bool parseCount(const std::string& text, unsigned long long& value) {
  if (text.empty() || !std::isdigit(static_cast<unsigned char>(text[0]))) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtoull(text.c_str(), &end, 10);
  return errno == 0 && end != nullptr && *end == '\0';
}

// A whole word as a signed integer ("-3", "17"); false for anything else ("1.5", "2/1").
bool parseInteger(const std::string& text, long long& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtoll(text.c_str(), &end, 10);
  return errno == 0 && end != text.c_str() && *end == '\0';
}

// ---------------------------------------------------------------------------------------
// PLY pre-check: walks the header and the body without storing anything, so that every
// count CGAL will trust has been checked against the bytes that are really there.

struct PlyProperty {
  std::string name;
  bool is_list = false;
  std::string type;       // scalar type, or the list's item type
  std::string size_type;  // list only
};

struct PlyElement {
  std::string name;
  unsigned long long count = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

// Byte size of a PLY scalar type as CGAL understands it; 0 for an unknown type.
int plyTypeSize(const std::string& type) {
  if (type == "char" || type == "int8" || type == "uchar" || type == "uint8") return 1;
  if (type == "short" || type == "int16" || type == "ushort" || type == "uint16") return 2;
  if (type == "int" || type == "int32" || type == "uint" || type == "uint32") return 4;
  if (type == "float" || type == "float32") return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

bool isPlyFloatType(const std::string& type) {
  return type == "float" || type == "float32" || type == "double" || type == "float64";
}

bool isPlyIntegerType(const std::string& type) {
  return plyTypeSize(type) > 0 && !isPlyFloatType(type);
}

bool isPlyIndexType(const std::string& type) {
  return type == "int" || type == "int32" || type == "uint" || type == "uint32";
}

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::size_t body_offset = 0;
};

// Parses "property ..." of the current element; returns an error or "".
std::string parsePlyProperty(std::istringstream& line, PlyElement& element) {
  PlyProperty p;
  std::string type;
  if (!(line >> type)) return "incomplete property line";
  if (type == "list") {
    p.is_list = true;
    if (!(line >> p.size_type >> p.type >> p.name)) return "incomplete list property line";
    if (!isPlyIntegerType(p.size_type))
      return "list length type " + quotedWord(p.size_type) + " is not an integer type";
    if (plyTypeSize(p.type) == 0) return "unknown list item type " + quotedWord(p.type);
  } else {
    p.type = type;
    if (!(line >> p.name)) return "property without a name";
    if (plyTypeSize(p.type) == 0) return "unknown property type " + quotedWord(p.type);
  }
  element.properties.push_back(p);
  return "";
}

std::string parsePlyHeader(const std::string& bytes, PlyHeader& header) {
  std::size_t pos = 0;
  int line_number = 0;
  while (pos < bytes.size()) {
    std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) eol = bytes.size();
    std::istringstream line(bytes.substr(pos, eol - pos));
    pos = std::min(bytes.size(), eol + 1);
    ++line_number;
    const std::string where = "line " + std::to_string(line_number) + ": ";
    std::string keyword;
    line >> keyword;
    if (line_number == 1) {
      if (keyword != "ply") return where + "not a PLY file (first line is not 'ply')";
      continue;
    }
    if (line_number == 2) {
      std::string format;
      line >> format;
      if (keyword != "format") return where + "expected 'format ...'";
      if (format == "ascii") {
        header.format = PlyFormat::kAscii;
      } else if (format == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittle;
      } else if (format == "binary_big_endian") {
        header.format = PlyFormat::kBinaryBig;
      } else {
        return where + "unknown format " + quotedWord(format);
      }
      continue;
    }
    if (keyword == "end_header") {
      header.body_offset = pos;
      return "";
    }
    if (keyword == "element") {
      PlyElement element;
      std::string count;
      if (!(line >> element.name >> count) || !parseCount(count, element.count))
        return where + "expected 'element <name> <count>'";
      // Every item takes at least a byte; CGAL loops over the count even for an element
      // without properties, so a corrupt count could otherwise spin for ages.
      if (element.count > bytes.size())
        return where + "element count " + count + " is larger than the file";
      header.elements.push_back(element);
    } else if (keyword == "property") {
      if (header.elements.empty()) return where + "property before any element";
      const std::string error = parsePlyProperty(line, header.elements.back());
      if (!error.empty()) return where + error;
    }
    // comment, obj_info and blank lines carry nothing we need.
  }
  return "header has no end_header line";
}

const PlyProperty* findPlyProperty(const PlyElement& element, const std::string& name) {
  for (const PlyProperty& p : element.properties)
    if (p.name == name) return &p;
  return nullptr;
}

// CGAL reads x, y, z through a float-or-double cast it does not check, and face indices
// only as 32-bit lists; anything else must be refused here.
std::string checkPlySemantics(const PlyHeader& header) {
  for (const PlyElement& e : header.elements) {
    if (e.name == "vertex" || e.name == "vertices") {
      for (const char* axis : {"x", "y", "z"}) {
        const PlyProperty* p = findPlyProperty(e, axis);
        if (p == nullptr) return std::string("element vertex: no '") + axis + "' property";
        if (p->is_list || !isPlyFloatType(p->type))
          return std::string("element vertex: property '") + axis + "' must be float or double";
      }
    } else if (e.name == "face" || e.name == "faces") {
      const PlyProperty* p = findPlyProperty(e, "vertex_indices");
      if (p == nullptr) p = findPlyProperty(e, "vertex_index");
      if (p == nullptr) return "element face: no 'vertex_indices' property";
      if (!p->is_list || !isPlyIndexType(p->type))
        return "element face: 'vertex_indices' must be a list of int or uint";
    }
  }
  return "";
}

std::uint64_t readUnsigned(const char* data, int size, bool big_endian) {
  std::uint64_t value = 0;
  for (int i = 0; i < size; ++i) {
    const int k = big_endian ? i : size - 1 - i;
    value = (value << 8) | static_cast<unsigned char>(data[k]);
  }
  return value;
}

// Reads a binary list length; negative signed lengths come back as "too large".
std::uint64_t readBinaryListLength(const char* data, const std::string& type, bool big_endian) {
  const int size = plyTypeSize(type);
  const std::uint64_t raw = readUnsigned(data, size, big_endian);
  const bool is_signed = type == "char" || type == "int8" || type == "short" || type == "int16" ||
                         type == "int" || type == "int32";
  if (is_signed && (raw >> (8 * size - 1)) != 0) return std::numeric_limits<std::uint64_t>::max();
  return raw;
}

std::string plyItemWhere(const PlyElement& e, unsigned long long item) {
  return "element " + shownText(e.name) + " " + std::to_string(item) + ": ";
}

// Walks the declared elements; `pos` ends where the last one does.
std::string walkPlyBinary(const std::string& bytes, const PlyHeader& header, std::size_t& pos) {
  const bool big_endian = header.format == PlyFormat::kBinaryBig;
  pos = header.body_offset;
  for (const PlyElement& e : header.elements) {
    for (unsigned long long item = 0; item < e.count; ++item) {
      for (const PlyProperty& p : e.properties) {
        const std::size_t remaining = bytes.size() - pos;
        if (!p.is_list) {
          const std::size_t size = static_cast<std::size_t>(plyTypeSize(p.type));
          if (remaining < size) return plyItemWhere(e, item) + "file is truncated";
          pos += size;
          continue;
        }
        const std::size_t length_size = static_cast<std::size_t>(plyTypeSize(p.size_type));
        if (remaining < length_size) return plyItemWhere(e, item) + "file is truncated";
        const std::uint64_t length =
            readBinaryListLength(bytes.data() + pos, p.size_type, big_endian);
        pos += length_size;
        const std::size_t item_size = static_cast<std::size_t>(plyTypeSize(p.type));
        if (length > (bytes.size() - pos) / item_size)
          return plyItemWhere(e, item) + "list length " + std::to_string(length) +
                 " runs past the end of the file";
        pos += static_cast<std::size_t>(length) * item_size;
      }
    }
  }
  return "";
}

// Next whitespace-separated token of an ASCII body, or "" at the end.
std::string nextToken(const std::string& bytes, std::size_t& pos) {
  while (pos < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
  const std::size_t begin = pos;
  while (pos < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
  return bytes.substr(begin, pos - begin);
}

std::string walkPlyAscii(const std::string& bytes, const PlyHeader& header, std::size_t& pos) {
  pos = header.body_offset;
  for (const PlyElement& e : header.elements) {
    for (unsigned long long item = 0; item < e.count; ++item) {
      for (const PlyProperty& p : e.properties) {
        const std::string token = nextToken(bytes, pos);
        if (token.empty()) return plyItemWhere(e, item) + "file is truncated";
        if (!p.is_list) continue;
        unsigned long long length = 0;
        if (!parseCount(token, length))
          return plyItemWhere(e, item) + "list length " + quotedWord(token) +
                 " is not a count (do the header's element counts match the data?)";
        // Every list entry needs at least one character and one separator.
        if (length > (bytes.size() - pos) / 2 + 1)
          return plyItemWhere(e, item) + "list length " + token + " runs past the end of the file";
        for (unsigned long long k = 0; k < length; ++k) {
          if (nextToken(bytes, pos).empty()) return plyItemWhere(e, item) + "file is truncated";
        }
      }
    }
  }
  return "";
}

// "161 vertices and 254 faces": what the header declares, for a message.
std::string declaredElements(const PlyHeader& header) {
  std::string text;
  for (std::size_t k = 0; k < header.elements.size(); ++k) {
    const PlyElement& e = header.elements[k];
    std::string name = shownText(e.name);
    if (e.count != 1) name = name == "vertex" ? "vertices" : name.back() == 's' ? name : name + "s";
    if (k > 0) text += k + 1 == header.elements.size() ? " and " : ", ";
    text += std::to_string(e.count) + " " + name;
  }
  return text.empty() ? "no elements" : text;
}

// 1-based number of the line holding bytes[pos].
std::size_t lineOf(const std::string& bytes, std::size_t pos) {
  return 1 + static_cast<std::size_t>(
                 std::count(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(pos), '\n'));
}

// Only whitespace (a final newline) may follow the last declared element. CGAL reads the
// counts the header declares and stops: a header that counts 251 faces of 254 lost three
// faces without a word, and anything after them (a second mesh pasted in) was ignored.
std::string checkPlyEnd(const std::string& bytes, const PlyHeader& header, std::size_t end) {
  std::size_t first = end;
  while (first < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[first]))) ++first;
  if (first == bytes.size()) return "";
  const std::string declared = "the header declares " + declaredElements(header);
  const std::string match = ": the header's element counts must match the data";
  if (header.format != PlyFormat::kAscii)
    return "byte " + std::to_string(end) + ": " + declared + ", but " +
           std::to_string(bytes.size() - end) + " more bytes follow the last one" + match;
  // Lines holding data after the last element; the line it ends on counts when data follows
  // on it.
  const std::size_t first_line = lineOf(bytes, first);
  const bool same_line = first_line == lineOf(bytes, end);
  std::size_t lines = 0;
  std::size_t pos = first;
  while (pos < bytes.size()) {
    std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) eol = bytes.size();
    if (std::any_of(bytes.begin() + static_cast<std::ptrdiff_t>(pos),
                    bytes.begin() + static_cast<std::ptrdiff_t>(eol),
                    [](char c) { return !std::isspace(static_cast<unsigned char>(c)); }))
      ++lines;
    pos = eol + 1;
  }
  const std::string follow =
      same_line
          ? "more values follow on this line" + (lines > 1
                                                     ? " and on " + std::to_string(lines - 1) +
                                                           " more line" + (lines > 2 ? "s" : "")
                                                     : std::string())
          : std::to_string(lines) + (lines == 1 ? " more line follows" : " more lines follow");
  return "line " + std::to_string(first_line) + ": " + declared + ", but " + follow + match;
}

std::string checkPly(const std::string& bytes) {
  PlyHeader header;
  std::string error = parsePlyHeader(bytes, header);
  if (error.empty()) error = checkPlySemantics(header);
  if (!error.empty()) return error;
  std::size_t end = 0;
  error = header.format == PlyFormat::kAscii ? walkPlyAscii(bytes, header, end)
                                             : walkPlyBinary(bytes, header, end);
  return error.empty() ? checkPlyEnd(bytes, header, end) : error;
}

// ---------------------------------------------------------------------------------------
// STL pre-check.

float readFloatLittleEndian(const char* data) {
  const std::uint32_t bits = static_cast<std::uint32_t>(readUnsigned(data, 4, false));
  float value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

// A binary STL is recognised by its size (84 + 50 bytes per facet), because many binary
// files start their 80-byte header with "solid" and CGAL would first try them as ASCII.
// Binary coordinates must be finite: CGAL welds points in a std::map, and a NaN makes its
// ordering inconsistent, so a NaN vertex would silently be merged into an unrelated one.
std::string prepareStl(std::string& bytes) {
  if (bytes.size() < 84) return "";
  const std::uint64_t facets = readUnsigned(bytes.data() + 80, 4, false);
  if (bytes.size() != 84 + 50 * facets) {
    // ASCII (CGAL skips blanks before "solid"), or a binary file whose count does not match
    // its size. A binary file shorter than its count was reported as a bad ASCII 'vertex'
    // line; one holding more whole facets than its count lost them without a word (CGAL
    // reads what the count gives: 349 of 350 facets), or was refused for its landmarks (3 of
    // 350): say what it is.
    const std::size_t first = bytes.find_first_not_of(" \t\r\n");
    const bool ascii = first != std::string::npos && bytes.compare(first, 5, "solid") == 0 &&
                       bytes.find('\0') == std::string::npos;
    if (ascii) return "";
    const std::string counted =
        "a binary STL of " + std::to_string(facets) + " facets (the count at byte 80) has " +
        std::to_string(84 + 50 * facets) + " bytes, this file " + std::to_string(bytes.size());
    if (bytes.size() < 84 + 50 * facets) return counted + ": cut short";
    // Bytes after the facets that make no whole facet, or only zeros (a block's padding), are
    // an exporter's padding: read.
    const std::size_t extra = bytes.size() - 84 - 50 * facets;
    if (extra % 50 != 0 || bytes.find_first_not_of('\0', 84 + 50 * facets) == std::string::npos)
      return "";
    return counted + ": it holds " + std::to_string(facets + extra / 50) +
           " facets, the count is wrong (re-export the mesh)";
  }
  for (std::uint64_t f = 0; f < facets; ++f) {
    const char* vertices = bytes.data() + 84 + 50 * f + 12;  // skip the facet normal
    for (int k = 0; k < 9; ++k) {
      if (!std::isfinite(readFloatLittleEndian(vertices + 4 * k)))
        return "facet " + std::to_string(f) + ": non-finite vertex coordinate";
    }
  }
  if (bytes.compare(0, 5, "solid") == 0) std::fill(bytes.begin(), bytes.begin() + 80, 'x');
  return "";
}

// ---------------------------------------------------------------------------------------
// OFF pre-check: CGAL resizes its point and polygon vectors to the header counts and each
// polygon to the corner count at the start of its line, unchecked. The check assumes the
// usual layout, one vertex or face per line (CGAL itself reads faces line by line).

struct OffLine {
  int number = 0;  // 1-based
  std::vector<std::string> words;
};

// Non-empty lines with '#' comments removed.
std::vector<OffLine> offLines(const std::string& bytes) {
  std::vector<OffLine> lines;
  std::size_t pos = 0;
  int number = 0;
  while (pos < bytes.size()) {
    std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) eol = bytes.size();
    ++number;
    std::string text = bytes.substr(pos, eol - pos);
    text = text.substr(0, text.find('#'));
    std::istringstream in(text);
    OffLine line{number, {}};
    for (std::string word; in >> word;) line.words.push_back(word);
    if (!line.words.empty()) lines.push_back(std::move(line));
    pos = eol + 1;
  }
  return lines;
}

std::string checkOff(const std::string& bytes) {
  const std::vector<OffLine> lines = offLines(bytes);
  if (lines.empty() || lines[0].words[0].find("OFF") == std::string::npos)
    return "line 1: not an OFF file (no OFF keyword)";
  const std::string& keyword = lines[0].words[0];
  if (lines[0].words.size() > 1 && lines[0].words[1] == "BINARY")
    return "line " + std::to_string(lines[0].number) + ": binary OFF is not supported";
  // The counts may follow the keyword on its line; "nOFF" puts a dimension first.
  std::vector<std::string> header(lines[0].words.begin() + 1, lines[0].words.end());
  std::size_t next = 1;
  const std::size_t needed = keyword.find("nOFF") != std::string::npos ? 3 : 2;
  while (header.size() < needed && next < lines.size()) {
    header.insert(header.end(), lines[next].words.begin(), lines[next].words.end());
    ++next;
  }
  unsigned long long counts[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    const std::size_t at = needed - 2 + static_cast<std::size_t>(k);
    if (at >= header.size() || !parseCount(header[at], counts[k]))
      return "header: expected vertex and face counts";
  }
  if (counts[0] > lines.size() || counts[1] > lines.size())
    return "header: vertex or face count is larger than the file";
  const std::size_t first_face = next + static_cast<std::size_t>(counts[0]);
  for (std::size_t f = 0; f < counts[1]; ++f) {
    if (first_face + f >= lines.size()) return "header: the file has fewer faces than declared";
    const OffLine& line = lines[first_face + f];
    unsigned long long corners = 0;
    if (!parseCount(line.words[0], corners) || corners > line.words.size() - 1)
      return "line " + std::to_string(line.number) + ": face " + std::to_string(f) +
             " does not list the corners it declares (do the header's counts match the data?)";
    // CGAL refuses an index outside 0..#V-1 with a bare failure. A word that is not an
    // integer is left to CGAL (and its hint).
    for (std::size_t k = 1; k <= corners; ++k) {
      long long index = 0;
      if (!parseInteger(line.words[k], index)) continue;
      if (index >= 0 && static_cast<unsigned long long>(index) < counts[0]) continue;
      return "line " + std::to_string(line.number) + ": face " + std::to_string(f) +
             ": vertex index " + line.words[k] + " is out of range: the header declares " +
             std::to_string(counts[0]) + " vertices, numbered 0 to " +
             std::to_string(static_cast<long long>(counts[0]) - 1);
    }
  }
  // As in a PLY, CGAL reads the declared counts and ignores the rest: a header counting too
  // few faces dropped the others without a word.
  const std::size_t end = first_face + static_cast<std::size_t>(counts[1]);
  if (end < lines.size()) {
    return "line " + std::to_string(lines[end].number) + ": the header declares " +
           counted(counts[0], "vertex", "vertices") + " and " +
           counted(counts[1], "face", "faces") + ", but " +
           counted(lines.size() - end, "more line follows", "more lines follow") +
           ": the header's counts must match the data";
  }
  return "";
}

// ---------------------------------------------------------------------------------------
// OBJ: CGAL rejects any statement it does not know, including "l" (polyline), which
// readMesh documents as ignored. Such lines are dropped before CGAL sees the text. CGAL also
// takes a face's corners only after a space ("f\t1\t2\t3" read as a face with one corner),
// while the format separates words by any blank: tabs become spaces first.
void normaliseObjText(std::string& bytes) {
  std::replace(bytes.begin(), bytes.end(), '\t', ' ');
  std::string kept;
  kept.reserve(bytes.size());
  std::size_t pos = 0;
  while (pos < bytes.size()) {
    std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) eol = bytes.size();
    std::istringstream line(bytes.substr(pos, eol - pos));
    std::string keyword;
    line >> keyword;
    // Keep the newline so that the line count stays right.
    if (keyword != "l") kept.append(bytes, pos, eol - pos);
    if (eol < bytes.size()) kept += '\n';
    pos = eol + 1;
  }
  bytes.swap(kept);
}

// OBJ face indices count from 1, or back from the latest vertex when negative (-1 is the
// vertex defined last before the face). CGAL refuses an index beyond the vertex count with a
// bare failure, lets one just past the end through, and reads 0, which the format does not
// have, as one past the last vertex: each is refused here, naming the line and the face.
// Read as CGAL reads them: the integer that starts each word (the vertex of "3/1/2"), until
// a word that does not start with one (the rest is CGAL's, and shortPolygonProblem's).
std::string checkObjIndices(const std::string& bytes) {
  std::vector<std::pair<std::size_t, std::string>> lines;  // (number, text), 'v' and 'f' only
  long long vertices = 0;
  std::size_t pos = 0;
  for (std::size_t number = 1; pos < bytes.size(); ++number) {
    std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) eol = bytes.size();
    std::string text = bytes.substr(pos, eol - pos);
    pos = eol + 1;
    std::istringstream line(text);
    std::string keyword;
    line >> keyword;
    if (keyword == "v") ++vertices;
    if (keyword == "v" || keyword == "f") lines.emplace_back(number, std::move(text));
  }
  // The indices valid on a line after `before` vertices ("-1 to -0" read as a range when no
  // vertex came before the face).
  auto range = [&](long long before) {
    return "1 to " + std::to_string(vertices) +
           (before == 0 ? ", and none counting back: no vertex precedes this line"
                        : ", or -1 to -" + std::to_string(before) + " counting back");
  };
  long long before = 0;  // vertices defined before the line
  long long face = 0;
  for (const auto& [number, text] : lines) {
    std::istringstream line(text);
    std::string word;
    line >> word;
    if (word == "v") {
      ++before;
      continue;
    }
    const std::string where =
        "line " + std::to_string(number) + ": face " + std::to_string(face++) + ": vertex index ";
    while (line >> word) {
      char* end = nullptr;
      errno = 0;
      const long long index = std::strtoll(word.c_str(), &end, 10);
      if (end == word.c_str() || errno != 0 || index < INT_MIN || index > INT_MAX) break;
      const std::string shown = word.substr(0, static_cast<std::size_t>(end - word.c_str()));
      if (index == 0) return where + "0: OBJ numbers vertices from 1 (here " + range(before) + ")";
      if (index > vertices)
        return where + shown + " is out of range: the file has " + std::to_string(vertices) +
               " vertices (" + range(before) + ")";
      if (-index > before)
        return where + shown + " counts back past the first vertex: " + std::to_string(before) +
               " vertices precede this line (" + range(before) + ")";
    }
  }
  // CGAL refuses a file without faces with its bare "could not parse"; the other formats say
  // "no faces".
  if (face == 0)
    return vertices == 0 ? "no vertices and no faces (no 'v' or 'f' line: is this an OBJ file?)"
                         : "no faces (no 'f' line)";
  return "";
}

// True when some whitespace-separated word reads as a non-finite number ("nan", "-inf").
bool containsNonFiniteWord(const std::string& bytes) {
  std::size_t pos = 0;
  for (std::string word = nextToken(bytes, pos); !word.empty(); word = nextToken(bytes, pos)) {
    word = asciiLowercase(word);
    if (word[0] == '-' || word[0] == '+') word.erase(0, 1);
    if (word.rfind("nan", 0) == 0 || word.rfind("inf", 0) == 0) return true;
  }
  return false;
}

// ---------------------------------------------------------------------------------------
// Soup to Eigen.

// Maps a CGAL index back to an int without turning an out-of-range index into a valid one:
// CGAL stores negative file indices as huge size_t values, which come back negative here.
int toIndex(std::size_t index) {
  if (index <= static_cast<std::size_t>(INT_MAX)) return static_cast<int>(index);
  const auto as_signed = static_cast<long long>(index);
  if (as_signed < 0 && as_signed >= INT_MIN) return static_cast<int>(as_signed);
  return -1;
}

// Fan-triangulates (the caller has refused polygons with fewer than 3 corners).
// Indices are copied unchecked: the mesh validator reports out-of-range ones by face.
void soupToEigen(const std::vector<DoublePoint>& points, const std::vector<Polygon>& polygons,
                 Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  V.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    V(row, 0) = points[i].x();
    V(row, 1) = points[i].y();
    V(row, 2) = points[i].z();
  }
  Eigen::Index triangles = 0;
  for (const Polygon& p : polygons) triangles += static_cast<Eigen::Index>(p.size() - 2);
  F.resize(triangles, 3);
  Eigen::Index row = 0;
  for (const Polygon& p : polygons) {
    for (std::size_t k = 1; k + 1 < p.size(); ++k) {
      F(row, 0) = toIndex(p[0]);
      F(row, 1) = toIndex(p[k]);
      F(row, 2) = toIndex(p[k + 1]);
      ++row;
    }
  }
}

// "face N: has K corners; ..." for the first polygon with fewer than 3 corners, else "".
// Dropping it, as the fan triangulation would, leaves a hole the validator cannot see: the
// mesh would validate with a face missing. An OBJ face also comes out short when CGAL stops
// at an index it cannot read as an int (2147483648), which the message says.
std::string shortPolygonProblem(const std::vector<Polygon>& polygons,
                                const std::string& extension) {
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    const std::size_t corners = polygons[f].size();
    if (corners >= 3) continue;
    return "face " + std::to_string(f) + ": has " + std::to_string(corners) +
           (corners == 1 ? " corner" : " corners") +
           "; a face needs at least 3 (larger polygons are fan-triangulated)" +
           (extension == ".obj" ? "; an index that is not a number in int range ends the "
                                  "face's list early"
                                : "");
  }
  return "";
}

bool allIndicesBelow(const std::vector<Polygon>& polygons, std::size_t n) {
  for (const Polygon& p : polygons)
    for (std::size_t i : p)
      if (i >= n) return false;
  return true;
}

// Runs the CGAL reader for `extension` on the (pre-checked) bytes.
bool readSoup(const std::string& extension, const std::string& bytes,
              std::vector<DoublePoint>& points, std::vector<Polygon>& polygons) {
  std::istringstream in(bytes, std::ios::in | std::ios::binary);
  const auto quiet = CGAL::parameters::verbose(false);
  if (extension == ".ply") {
    CGAL::IO::set_mode(in, CGAL::IO::BINARY);
    return CGAL::IO::read_PLY(in, points, polygons, quiet);
  }
  if (extension == ".obj") return CGAL::IO::read_OBJ(in, points, polygons, quiet);
  if (extension == ".off") return CGAL::IO::read_OFF(in, points, polygons, quiet);
  if (extension == ".stl") {
    CGAL::IO::set_mode(in, CGAL::IO::BINARY);
    if (!CGAL::IO::read_STL(in, points, polygons, quiet)) return false;
    // The STL reader already merges identical points; the explicit weld keeps that
    // guarantee independent of the reader version.
    if (allIndicesBelow(polygons, points.size()))
      PMP::merge_duplicate_points_in_polygon_soup(points, polygons);
    return true;
  }
  return false;
}

// Where to look when CGAL refuses a file that passed the pre-checks: CGAL says no more than
// that it failed, and a bad token (a coordinate 1e400, a face index 1.5) is the usual cause.
std::string parseHint(const std::string& extension, bool text) {
  if (extension == ".ply" && text)
    return " (ASCII PLY: check that the header's element counts match the lines and that every "
           "value is a number of its property's type: coordinates within double range, face "
           "indices whole numbers)";
  if (extension == ".ply")
    return " (binary PLY: check the header's element counts and property types against the "
           "data)";
  if (extension == ".obj")
    return " (OBJ: check that every 'v' line has 3 numbers within double range and every 'f' "
           "line whole vertex numbers)";
  if (extension == ".off")
    return " (OFF: check the header's counts and that every value is a number: coordinates "
           "within double range, face indices whole numbers)";
  return " (STL: check that every 'vertex' line has 3 numbers within double range)";
}

bool readTriangleSoupImpl(const std::filesystem::path& path, Eigen::MatrixXd& V, Eigen::MatrixXi& F,
                          std::string& error) {
  const std::string extension = asciiLowercase(path.extension().string());
  if (extension != ".ply" && extension != ".obj" && extension != ".off" && extension != ".stl") {
    error = "unsupported extension " + quotedWord(path.extension().string());
    return false;
  }
  std::string bytes;
  if (!readWholeFile(path, bytes)) {
    error = cannotBeRead(path);
    return false;
  }
  if (extension == ".ply") error = checkPly(bytes);
  if (extension == ".off") error = checkOff(bytes);
  if (extension == ".stl") error = prepareStl(bytes);
  if (extension == ".obj") {
    normaliseObjText(bytes);
    error = checkObjIndices(bytes);
  }
  if (!error.empty()) return false;

  std::vector<DoublePoint> points;
  std::vector<Polygon> polygons;
  if (!readSoup(extension, bytes, points, polygons)) {
    const bool text = extension != ".ply" || bytes.find("format ascii") != std::string::npos;
    error = "CGAL could not parse the file";
    // CGAL's ASCII number parser accepts only digits, signs, '.' and exponents.
    if (text && containsNonFiniteWord(bytes))
      error += " (non-finite values such as 'nan' or 'inf' are not readable in this format)";
    else
      error += parseHint(extension, text);
    return false;
  }
  error = shortPolygonProblem(polygons, extension);
  if (!error.empty()) return false;
  soupToEigen(points, polygons, V, F);
  if (F.rows() == 0) {
    error = "no faces";
    return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------
// Self-intersections.

// Exact predicates: an intersection test must not flip on rounding for touching neighbours.
using EpickKernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using EpickPoint = EpickKernel::Point_3;

bool isDegenerate(const std::array<EpickPoint, 3>& t) { return CGAL::collinear(t[0], t[1], t[2]); }

// Same rules as CGAL's do_faces_intersect, but adjacency comes from shared vertex indices
// instead of mesh connectivity, so it works on non-manifold soups.
bool soupFacesIntersect(const std::vector<EpickPoint>& points, const Eigen::MatrixXi& F, int a,
                        int b) {
  std::array<int, 3> ia{F(a, 0), F(a, 1), F(a, 2)};
  std::array<int, 3> ib{F(b, 0), F(b, 1), F(b, 2)};
  std::vector<std::pair<int, int>> shared;  // (corner in a, corner in b)
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (ia[i] == ib[j]) shared.emplace_back(i, j);
  const auto P = [&](int index) -> const EpickPoint& {
    return points[static_cast<std::size_t>(index)];
  };
  const EpickKernel::Triangle_3 ta(P(ia[0]), P(ia[1]), P(ia[2]));
  const EpickKernel::Triangle_3 tb(P(ib[0]), P(ib[1]), P(ib[2]));
  if (shared.size() >= 3) return true;  // the same triangle twice
  if (shared.size() == 2) {
    // Across a shared edge only a coplanar fold-over counts.
    const int oa = 3 - shared[0].first - shared[1].first;
    const int ob = 3 - shared[0].second - shared[1].second;
    const EpickPoint& p = P(ia[shared[0].first]);
    const EpickPoint& q = P(ia[shared[1].first]);
    return CGAL::coplanar(p, q, P(ia[oa]), P(ib[ob])) &&
           CGAL::coplanar_orientation(p, q, P(ia[oa]), P(ib[ob])) == CGAL::POSITIVE;
  }
  if (shared.size() == 1) {
    const int i = shared[0].first;
    const int j = shared[0].second;
    const EpickKernel::Segment_3 sa(P(ia[(i + 1) % 3]), P(ia[(i + 2) % 3]));
    const EpickKernel::Segment_3 sb(P(ib[(j + 1) % 3]), P(ib[(j + 2) % 3]));
    return CGAL::do_intersect(ta, sb) || CGAL::do_intersect(tb, sa);
  }
  return CGAL::do_intersect(ta, tb);
}

int countSoupSelfIntersections(const std::vector<EpickPoint>& points, const Eigen::MatrixXi& F) {
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, int,
                                                        CGAL::Box_intersection_d::ID_EXPLICIT>;
  std::vector<Box> boxes;
  for (int f = 0; f < F.rows(); ++f) {
    const std::array<EpickPoint, 3> t{points[static_cast<std::size_t>(F(f, 0))],
                                      points[static_cast<std::size_t>(F(f, 1))],
                                      points[static_cast<std::size_t>(F(f, 2))]};
    if (isDegenerate(t)) continue;  // as in CGAL: a degenerate face has no box
    boxes.emplace_back(t[0].bbox() + t[1].bbox() + t[2].bbox(), f);
  }
  std::vector<const Box*> pointers;
  for (const Box& b : boxes) pointers.push_back(&b);
  std::set<std::pair<int, int>> pairs;
  CGAL::box_self_intersection_d(pointers.begin(), pointers.end(), [&](const Box* x, const Box* y) {
    const int a = std::min(x->info(), y->info());
    const int b = std::max(x->info(), y->info());
    if (soupFacesIntersect(points, F, a, b)) pairs.emplace(a, b);
  });
  return static_cast<int>(pairs.size());
}

int countMeshSelfIntersections(const std::vector<EpickPoint>& points,
                               const std::vector<std::array<std::size_t, 3>>& faces) {
  using Mesh = CGAL::Surface_mesh<EpickPoint>;
  using Face = boost::graph_traits<Mesh>::face_descriptor;
  Mesh mesh;
  PMP::polygon_soup_to_polygon_mesh(points, faces, mesh);
  std::vector<std::pair<Face, Face>> pairs;
  PMP::self_intersections(mesh, std::back_inserter(pairs));
  // CGAL reports a degenerate face as the pair (f, f); that is not a pair of triangles
  // (the mesh checks report degenerate faces on their own).
  return static_cast<int>(
      std::count_if(pairs.begin(), pairs.end(), [](const auto& p) { return p.first != p.second; }));
}

}  // namespace

// ---------------------------------------------------------------------------------------

int weldCoincidentVertices(Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  std::vector<DoublePoint> points;
  points.reserve(V.rows());
  for (Eigen::Index v = 0; v < V.rows(); ++v) points.emplace_back(V(v, 0), V(v, 1), V(v, 2));
  std::vector<Polygon> polygons(F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (Eigen::Index k = 0; k < F.cols(); ++k) polygons[f].push_back(F(f, k));
  const int merged =
      static_cast<int>(PMP::merge_duplicate_points_in_polygon_soup(points, polygons));
  if (merged == 0) return 0;
  V.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t v = 0; v < points.size(); ++v)
    V.row(v) << points[v].x(), points[v].y(), points[v].z();
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (Eigen::Index k = 0; k < F.cols(); ++k) F(f, k) = static_cast<int>(polygons[f][k]);
  return merged;
}

bool cgalReadTriangleSoup(const std::filesystem::path& path, Eigen::MatrixXd& V, Eigen::MatrixXi& F,
                          std::string& error) {
  error.clear();
  try {
    return readTriangleSoupImpl(path, V, F, error);
  } catch (const std::exception& e) {
    error = std::string("reader failed: ") + e.what();
  } catch (...) {
    error = "reader failed with an unknown exception";
  }
  return false;
}

struct SurfaceDistance::Impl {
  using Triangle = DoubleKernel::Triangle_3;
  using Iterator = std::vector<Triangle>::const_iterator;
  using Primitive = CGAL::AABB_triangle_primitive<DoubleKernel, Iterator>;
  using Traits = CGAL::AABB_traits<DoubleKernel, Primitive>;
  using Tree = CGAL::AABB_tree<Traits>;

  std::vector<Triangle> triangles;  // must outlive and never move under `tree`
  Tree tree;
};

// Triangles with an out-of-range index are skipped like degenerate ones: the distance is
// a measurement, and the mesh checks are where bad indices get reported.
SurfaceDistance::SurfaceDistance(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F)
    : impl_(std::make_unique<Impl>()) {
  const auto point = [&](int i) { return DoublePoint(V(i, 0), V(i, 1), V(i, 2)); };
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    bool valid = true;
    for (int k = 0; k < 3; ++k) valid = valid && F(f, k) >= 0 && F(f, k) < V.rows();
    if (!valid) continue;
    Impl::Triangle t(point(F(f, 0)), point(F(f, 1)), point(F(f, 2)));
    if (!t.is_degenerate()) impl_->triangles.push_back(t);
  }
  if (impl_->triangles.empty()) return;
  impl_->tree.insert(impl_->triangles.begin(), impl_->triangles.end());
  // Both structures are otherwise built lazily by the first query, which would race when
  // several threads query at once.
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
}

SurfaceDistance::~SurfaceDistance() = default;

// An empty surface (no valid triangle) is infinitely far away; `closest` becomes NaN.
double SurfaceDistance::distance(const Eigen::Vector3d& p, Eigen::Vector3d* closest) const {
  if (impl_->triangles.empty()) {
    if (closest != nullptr) closest->setConstant(std::numeric_limits<double>::quiet_NaN());
    return std::numeric_limits<double>::infinity();
  }
  const DoublePoint query(p.x(), p.y(), p.z());
  const DoublePoint c = impl_->tree.closest_point(query);
  if (closest != nullptr) *closest = Eigen::Vector3d(c.x(), c.y(), c.z());
  return std::sqrt(CGAL::squared_distance(query, c));
}

// Returns -1 when the count cannot be computed: an index out of range, a non-finite
// coordinate, or a CGAL failure. Degenerate triangles are not counted (see above).
// CGAL 5.5 has no triangle_soup_self_intersections, so a soup that is not a valid polygon
// mesh (non-manifold edges or vertices, repeated corners) goes through the soup version
// above, which applies CGAL's own adjacency rules to shared vertex indices.
int countSelfIntersections(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  try {
    if (V.cols() != 3 || F.cols() != 3 || !V.allFinite()) return -1;
    if (F.size() > 0 && (F.minCoeff() < 0 || F.maxCoeff() >= V.rows())) return -1;
    std::vector<EpickPoint> points;
    points.reserve(static_cast<std::size_t>(V.rows()));
    for (Eigen::Index i = 0; i < V.rows(); ++i) points.emplace_back(V(i, 0), V(i, 1), V(i, 2));
    std::vector<std::array<std::size_t, 3>> faces;
    for (Eigen::Index f = 0; f < F.rows(); ++f)
      faces.push_back({static_cast<std::size_t>(F(f, 0)), static_cast<std::size_t>(F(f, 1)),
                       static_cast<std::size_t>(F(f, 2))});
    if (PMP::is_polygon_soup_a_polygon_mesh(faces))
      return countMeshSelfIntersections(points, faces);
    return countSoupSelfIntersections(points, F);
  } catch (...) {
    return -1;
  }
}

}  // namespace chordfit
