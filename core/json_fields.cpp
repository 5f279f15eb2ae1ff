#include "core/json_fields.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include "core/atomic_file.h"

namespace chordfit {

namespace {

// nlohmann reports a byte offset; people look for line and column.
std::string lineColumn(const std::string& text, std::size_t byte) {
  std::size_t line = 1;
  std::size_t column = 1;
  for (std::size_t i = 0; i < text.size() && i + 1 < byte; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

// nlohmann's message starts with "[json.exception.parse_error.101] parse error at line ..";
// keep only the reason after the last ": ".
// nlohmann's message: "[json.exception.parse_error.101] parse error at line 1, column 3:
// syntax error while parsing value - invalid literal; last read: '[[N'". The reason is what
// follows the position (the last ": " would cut it to "'[[N'").
std::string parseReason(const std::string& message) {
  const std::size_t column = message.find("column ");
  const std::size_t colon = message.find(": ", column == std::string::npos ? 0 : column);
  return colon == std::string::npos ? message : message.substr(colon + 2);
}

// Edits (insertions, deletions, substitutions) that turn a into b.
std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// Finds keys given twice in one object, from nlohmann's parse events. JSON leaves duplicates
// to the reader and nlohmann keeps the last one without a word: a case.json with two "mesh"
// keys simulated the second mesh, a cord with two "rest_length_mm" the second length.
class DuplicateKeys {
 public:
  bool operator()(int /*depth*/, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    switch (event) {
      case Event::object_start:
      case Event::array_start:
        stack_.push_back(Frame{event == Event::object_start, {}, {}, 0});
        break;
      case Event::key:
        if (!stack_.empty() && stack_.back().object) {
          Frame& object = stack_.back();
          object.key = parsed.get<std::string>();
          if (++object.seen[object.key] == 2) found_.push_back(fieldPath(objectPath(), object.key));
        }
        break;
      case Event::value:
        if (!stack_.empty() && !stack_.back().object) ++stack_.back().index;
        break;
      case Event::object_end:
      case Event::array_end:
        if (!stack_.empty()) stack_.pop_back();
        if (!stack_.empty() && !stack_.back().object) ++stack_.back().index;
        break;
    }
    return true;
  }

  // "cords[1].rest_length_mm" of each key given twice (or more) in its object, in file order.
  const std::vector<std::string>& found() const { return found_; }

 private:
  struct Frame {
    bool object = false;
    std::map<std::string, int> seen;  // an object's keys so far, with their counts
    std::string key;                  // an object's current key
    std::size_t index = 0;            // an array's current element
  };

  // The path of the innermost object, the one whose key was just read.
  std::string objectPath() const {
    std::string path;
    for (std::size_t k = 0; k + 1 < stack_.size(); ++k)
      path = stack_[k].object ? fieldPath(path, stack_[k].key) : indexPath(path, stack_[k].index);
    return path;
  }

  std::vector<Frame> stack_;
  std::vector<std::string> found_;
};

}  // namespace

std::optional<nlohmann::json> parseJson(const std::string& text, const std::string& file,
                                        Diagnostics& diagnostics) {
  try {
    DuplicateKeys duplicates;
    nlohmann::json document = nlohmann::json::parse(
        text, [&duplicates](int depth, nlohmann::json::parse_event_t event,
                            nlohmann::json& parsed) { return duplicates(depth, event, parsed); });
    constexpr std::size_t kMaxReported = 10;
    const std::vector<std::string>& found = duplicates.found();
    for (std::size_t k = 0; k < found.size() && k < kMaxReported; ++k)
      diagnostics.error(file, found[k],
                        "duplicate key: given more than once in this object, and only one of "
                        "its values would be read: keep one");
    if (found.size() > kMaxReported)
      diagnostics.error(file, "",
                        std::to_string(found.size() - kMaxReported) + " more duplicate keys");
    if (!found.empty()) return std::nullopt;
    return document;
  } catch (const nlohmann::json::parse_error& e) {
    diagnostics.error(file, lineColumn(text, e.byte), "malformed JSON: " + parseReason(e.what()));
  } catch (const nlohmann::json::exception& e) {
    // Syntactically valid but unrepresentable, e.g. a number beyond double range (1e999):
    // nlohmann reports it as out_of_range without a position.
    const std::string message = e.what();
    const std::size_t tag_end = message.find("] ");  // drop "[json.exception.<id>] "
    diagnostics.error(file, "",
                      "unreadable JSON: " +
                          (tag_end == std::string::npos ? message : message.substr(tag_end + 2)));
  }
  return std::nullopt;
}

std::optional<std::string> readInputText(const std::filesystem::path& path, const std::string& file,
                                         const std::string& what, Diagnostics& diagnostics) {
  if (const std::string problem = inputFileProblem(path, what); !problem.empty()) {
    diagnostics.error(file, "", problem);
    return std::nullopt;
  }
  std::string text;
  if (!readWholeFile(path, text)) {
    diagnostics.error(file, "", cannotBeRead(path));
    return std::nullopt;
  }
  return text;
}

std::optional<nlohmann::json> loadJsonFile(const std::filesystem::path& path,
                                           const std::string& file, Diagnostics& diagnostics) {
  const std::optional<std::string> text = readInputText(path, file, "a JSON file", diagnostics);
  if (!text) return std::nullopt;
  return parseJson(*text, file, diagnostics);
}

std::string jsonTypeName(const nlohmann::json& value) {
  if (value.is_object()) return "object";
  if (value.is_array()) return "array";
  if (value.is_string()) return "string";
  if (value.is_boolean()) return "boolean";
  if (value.is_number()) return "number";
  return "null";
}

std::string fieldPath(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

std::string indexPath(const std::string& parent, std::size_t index) {
  return parent + "[" + std::to_string(index) + "]";
}

std::string typoSuggestion(const std::string& key, const std::vector<std::string>& known) {
  // Two edits catch a dropped or doubled letter and a swap in a word; in a key of four
  // letters or fewer two edits pair unrelated words ("id" -> "tip"), so one there.
  const std::size_t max_typo_edits = key.size() <= 4 ? 1 : 2;
  std::string nearest;
  std::size_t nearest_edits = max_typo_edits + 1;
  for (const std::string& name : known) {
    const std::size_t edits = editDistance(key, name);
    if (edits < nearest_edits) {
      nearest_edits = edits;
      nearest = name;
    }
  }
  if (nearest.empty()) {
    // A key without its unit ("youngs_modulus" for "youngs_modulus_mpa", "pressure" for
    // "pressure_mmhg"): the one known key that starts with it and a '_'.
    for (const std::string& name : known) {
      if (key.size() >= 3 && name.size() > key.size() + 1 &&
          name.compare(0, key.size(), key) == 0 && name[key.size()] == '_') {
        if (!nearest.empty()) return "";  // more than one: no guess
        nearest = name;
      }
    }
  }
  return nearest.empty() ? "" : "; did you mean \"" + nearest + "\"?";
}

bool JsonFields::knownKeys(const nlohmann::json& object, const std::string& where,
                           std::initializer_list<const char*> known) {
  if (!object.is_object()) return true;  // the type is reported where the object is read
  const std::vector<std::string> names(known.begin(), known.end());
  bool ok = true;
  for (const auto& item : object.items()) {
    const std::string& key = item.key();
    if (std::find(names.begin(), names.end(), key) != names.end()) continue;
    error(fieldPath(where, key), "unknown key" + typoSuggestion(key, names));
    ok = false;
  }
  return ok;
}

void JsonFields::error(const std::string& where, const std::string& what) {
  diagnostics_.error(file_, where, what);
}

void JsonFields::typeError(const std::string& where, const std::string& expected,
                           const nlohmann::json& got) {
  error(where, "expected " + expected + ", got " + jsonTypeName(got));
}

const nlohmann::json* JsonFields::member(const nlohmann::json& object, const std::string& where,
                                         const std::string& key, bool required) {
  if (!object.is_object()) {
    typeError(where.empty() ? "(top level)" : where, "an object", object);
    return nullptr;
  }
  const auto it = object.find(key);
  if (it == object.end() || it->is_null()) {
    if (required) error(fieldPath(where, key), "required field is missing");
    return nullptr;
  }
  return &*it;
}

bool JsonFields::number(const nlohmann::json& value, const std::string& where, double& out) {
  if (!value.is_number()) {
    typeError(where, "a number", value);
    return false;
  }
  out = value.get<double>();
  if (!std::isfinite(out)) {
    error(where, "number is not finite");
    return false;
  }
  return true;
}

bool JsonFields::integer(const nlohmann::json& value, const std::string& where, int& out) {
  // A whole number written with a fraction part (2000.0, as scripts that hold every number as a
  // float write it) is that integer; 2000.5 is named, not called "number".
  if (value.is_number_float()) {
    const double real = value.get<double>();
    if (!std::isfinite(real) || real != std::floor(real)) {
      error(where, "expected an integer, got " + value.dump());
      return false;
    }
    if (real < std::numeric_limits<int>::min() || real > std::numeric_limits<int>::max()) {
      error(where, "integer out of range");
      return false;
    }
    out = static_cast<int>(real);
    return true;
  }
  if (!value.is_number_integer()) {
    typeError(where, "an integer", value);
    return false;
  }
  const auto wide = value.get<long long>();
  if (wide < std::numeric_limits<int>::min() || wide > std::numeric_limits<int>::max()) {
    error(where, "integer out of range");
    return false;
  }
  out = static_cast<int>(wide);
  return true;
}

bool JsonFields::text(const nlohmann::json& value, const std::string& where, std::string& out) {
  if (!value.is_string()) {
    typeError(where, "a string", value);
    return false;
  }
  out = value.get<std::string>();
  return true;
}

bool JsonFields::boolean(const nlohmann::json& value, const std::string& where, bool& out) {
  if (!value.is_boolean()) {
    typeError(where, "true or false", value);
    return false;
  }
  out = value.get<bool>();
  return true;
}

bool JsonFields::vec3(const nlohmann::json& value, const std::string& where, Eigen::Vector3d& out) {
  if (!value.is_array() || value.size() != 3) {
    error(where, "expected an array of 3 numbers, got " +
                     (value.is_array() ? "an array of " + std::to_string(value.size())
                                       : jsonTypeName(value)));
    return false;
  }
  for (int k = 0; k < 3; ++k) {
    if (!number(value[k], indexPath(where, k), out(k))) return false;
  }
  return true;
}

bool JsonFields::points(const nlohmann::json& value, const std::string& where,
                        Eigen::MatrixXd& out) {
  if (!value.is_array()) {
    typeError(where, "an array of [x, y, z] points", value);
    return false;
  }
  out.resize(static_cast<Eigen::Index>(value.size()), 3);
  bool ok = true;
  for (std::size_t i = 0; i < value.size(); ++i) {
    Eigen::Vector3d p;
    if (vec3(value[i], indexPath(where, i), p)) {
      out.row(static_cast<Eigen::Index>(i)) = p.transpose();
    } else {
      ok = false;
    }
  }
  return ok;
}

bool JsonFields::integers(const nlohmann::json& value, const std::string& where,
                          Eigen::VectorXi& out) {
  if (!value.is_array()) {
    typeError(where, "an array of integers", value);
    return false;
  }
  out.resize(static_cast<Eigen::Index>(value.size()));
  bool ok = true;
  for (std::size_t i = 0; i < value.size(); ++i) {
    int v = 0;
    if (integer(value[i], indexPath(where, i), v)) {
      out(static_cast<Eigen::Index>(i)) = v;
    } else {
      ok = false;
    }
  }
  return ok;
}

}  // namespace chordfit
