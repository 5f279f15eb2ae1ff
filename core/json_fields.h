// Typed access to JSON input with precise messages: every reader of the project's JSON
// formats (case.json, cord sets, point lists, tracings) reports problems as
//   <file>: <field path>: expected <type>, got <type>
// through one of these, so the wording is the same everywhere.
#pragma once

#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/diagnostics.h"

namespace chordfit {

// Parses JSON text; on a syntax error adds "line L, column C: <reason>" and returns nullopt,
// and so on a key given twice in one object ("<path>.<key>: duplicate key: ..."; nlohmann
// would keep the last value without a word). Every JSON input goes through here.
std::optional<nlohmann::json> parseJson(const std::string& text, const std::string& file,
                                        Diagnostics& diagnostics);

// Reads and parses a file; a missing file is reported as "file not found", and whatever else
// inputFileProblem refuses (a directory, a device, an empty path) as it says.
std::optional<nlohmann::json> loadJsonFile(const std::filesystem::path& path,
                                           const std::string& file, Diagnostics& diagnostics);

// The reading half of loadJsonFile, for a reader that looks at the text itself when it does
// not parse (readCurve): its bytes, or nullopt with the problem reported. `what`: the kind of
// file the messages name ("a JSON file", "a curve file").
std::optional<std::string> readInputText(const std::filesystem::path& path, const std::string& file,
                                         const std::string& what, Diagnostics& diagnostics);

// "object", "array", "string", "number", "boolean", "null".
std::string jsonTypeName(const nlohmann::json& value);

// "; did you mean \"<name>\"?" for the name in `known` a typo of `key` explains (one or two
// edits), or "" when none does: the tail of an "unknown key" message.
std::string typoSuggestion(const std::string& key, const std::vector<std::string>& known);

class JsonFields {
 public:
  JsonFields(std::string file, Diagnostics& diagnostics)
      : file_(std::move(file)), diagnostics_(diagnostics) {}

  const std::string& file() const { return file_; }
  Diagnostics& diagnostics() { return diagnostics_; }

  // Member `key` of `object` (whose own path is `where`). Reports a missing required member
  // and a non-object parent. Returns nullptr when absent or on error.
  const nlohmann::json* member(const nlohmann::json& object, const std::string& where,
                               const std::string& key, bool required);

  bool number(const nlohmann::json& value, const std::string& where, double& out);
  bool integer(const nlohmann::json& value, const std::string& where, int& out);
  bool text(const nlohmann::json& value, const std::string& where, std::string& out);
  bool boolean(const nlohmann::json& value, const std::string& where, bool& out);
  // [x, y, z] of finite numbers.
  bool vec3(const nlohmann::json& value, const std::string& where, Eigen::Vector3d& out);
  // [[x, y, z], ...] of finite numbers -> #P by 3.
  bool points(const nlohmann::json& value, const std::string& where, Eigen::MatrixXd& out);
  // [i, j, ...] of integers.
  bool integers(const nlohmann::json& value, const std::string& where, Eigen::VectorXi& out);

  // Reports every key of `object` (whose own path is `where`) that is not in `known`, as
  // "<where>.<key>: unknown key", suggesting the nearest known key when a typo explains it
  // (a misspelt optional key would otherwise just go missing). Returns whether all are known.
  bool knownKeys(const nlohmann::json& object, const std::string& where,
                 std::initializer_list<const char*> known);

  void error(const std::string& where, const std::string& what);
  void typeError(const std::string& where, const std::string& expected, const nlohmann::json& got);

 private:
  std::string file_;
  Diagnostics& diagnostics_;
};

// Path helpers for messages: field("a", "b") == "a.b", index("a", 2) == "a[2]".
std::string fieldPath(const std::string& parent, const std::string& key);
std::string indexPath(const std::string& parent, std::size_t index);

}  // namespace chordfit
