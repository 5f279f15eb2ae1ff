#include "core/curve_io.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/curve_csv.h"
#include "core/json_fields.h"
#include "core/quoted_text.h"
#include "core/text_case.h"

namespace chordfit {
namespace {

using json = nlohmann::json;

// Slicer's own reader (vtkMRMLMarkupsJsonStorageNode) assumes LPS when the field is absent.
constexpr const char* kDefaultCoordinateSystem = "LPS";

// Reads "coordinateSystem" of `object` and converts the curve's points from it to LPS in place.
bool toLps(const json& object, const std::string& where, JsonFields& fields, Curve& curve) {
  Eigen::MatrixXd& points = curve.points;
  std::string system = kDefaultCoordinateSystem;
  if (const json* value = fields.member(object, where, "coordinateSystem", false)) {
    if (!fields.text(*value, fieldPath(where, "coordinateSystem"), system)) return false;
  }
  curve.read_as_ras = system == "RAS";
  curve.other_frame_syntax = std::string("say \"coordinateSystem\": \"") +
                             (curve.read_as_ras ? "LPS" : "RAS") + "\" in the file";
  if (system == "RAS") {
    points.col(0) *= -1.0;  // R -> L
    points.col(1) *= -1.0;  // A -> P
  } else if (system != "LPS") {
    fields.error(fieldPath(where, "coordinateSystem"),
                 "expected \"LPS\" or \"RAS\", got " + quotedText(system));
    return false;
  }
  return true;
}

// Positions are millimetres everywhere in chordfit; other units would be silently wrong.
// Slicer writes the units as a string ("mm") or as a coded entry {"CodeValue": "mm", ...}.
bool checkUnits(const json& markup, const std::string& where, JsonFields& fields) {
  const json* value = fields.member(markup, where, "coordinateUnits", false);
  if (value == nullptr) return true;
  std::string field = fieldPath(where, "coordinateUnits");
  if (value->is_object() && value->contains("CodeValue")) {
    value = &(*value)["CodeValue"];
    field = fieldPath(field, "CodeValue");
  }
  if (!value->is_string()) return true;  // nothing we can interpret; Slicer's default is mm
  const std::string units = value->get<std::string>();
  if (units == "mm") return true;
  fields.error(field, "expected \"mm\", got " + quotedText(units));
  return false;
}

// Slicer keeps placeholder control points that were never placed; their positions are
// meaningless, so they are skipped.
bool isPlaced(const json& point) {
  const auto status = point.find("positionStatus");
  return status == point.end() || !status->is_string() || *status != "undefined";
}

bool readControlPoints(const json& markup, const std::string& where, JsonFields& fields,
                       Curve& curve) {
  Eigen::MatrixXd& points = curve.points;
  const std::string list_where = fieldPath(where, "controlPoints");
  const json* list = fields.member(markup, where, "controlPoints", true);
  if (list == nullptr) return false;
  if (!list->is_array()) {
    fields.typeError(list_where, "an array of control points", *list);
    return false;
  }
  points.resize(static_cast<Eigen::Index>(list->size()), 3);
  Eigen::Index placed = 0;
  bool ok = true;
  for (std::size_t i = 0; i < list->size(); ++i) {
    const json& point = (*list)[i];
    const std::string point_where = indexPath(list_where, i);
    if (!point.is_object()) {
      fields.typeError(point_where, "a control point object", point);
      ok = false;
      continue;
    }
    if (!isPlaced(point)) continue;
    const json* position = fields.member(point, point_where, "position", true);
    Eigen::Vector3d p;
    if (position == nullptr || !fields.vec3(*position, fieldPath(point_where, "position"), p)) {
      ok = false;
      continue;
    }
    points.row(placed++) = p.transpose();
    curve.point_wheres.push_back(fieldPath(point_where, "position"));
  }
  points.conservativeResize(placed, 3);
  return ok;
}

bool readMarkups(const json& document, JsonFields& fields, int markup_index, Curve& curve) {
  const json& markups = document["markups"];
  if (!markups.is_array()) {
    fields.typeError("markups", "an array", markups);
    return false;
  }
  if (markup_index < 0 || static_cast<std::size_t>(markup_index) >= markups.size()) {
    fields.error("markups", "markup " + std::to_string(markup_index) +
                                " requested, but the file has " + std::to_string(markups.size()));
    return false;
  }
  const std::string where = indexPath("markups", static_cast<std::size_t>(markup_index));
  const json& markup = markups[static_cast<std::size_t>(markup_index)];
  const json* type_value = fields.member(markup, where, "type", true);
  std::string type;
  if (type_value == nullptr || !fields.text(*type_value, fieldPath(where, "type"), type))
    return false;
  if (type != "Curve" && type != "ClosedCurve" && type != "Fiducial") {
    fields.error(fieldPath(where, "type"),
                 "expected \"Curve\", \"ClosedCurve\" or \"Fiducial\", got " + quotedText(type));
    return false;
  }
  curve.closed = type == "ClosedCurve";
  bool ok = checkUnits(markup, where, fields);
  ok = readControlPoints(markup, where, fields, curve) && ok;
  ok = ok && toLps(markup, where, fields, curve);
  if (ok && curve.points.rows() == 0) {
    fields.error(fieldPath(where, "controlPoints"), "no placed control points");
    return false;
  }
  return ok;
}

// {"points": [[x, y, z], ...], "closed": bool, "coordinateSystem": "LPS"|"RAS"} (the last
// two optional) or a bare [[x, y, z], ...].
bool readPointList(const json& document, JsonFields& fields, Curve& curve) {
  if (document.is_array()) {
    curve.closed = false;
    curve.other_frame_syntax =
        "give the points as {\"points\": [...], \"coordinateSystem\": \"RAS\"}";
    if (!fields.points(document, "", curve.points)) return false;
    if (curve.points.rows() == 0) {
      fields.error("(top level)", "no points");
      return false;
    }
    for (Eigen::Index k = 0; k < curve.points.rows(); ++k)
      curve.point_wheres.push_back(indexPath("", static_cast<std::size_t>(k)));
    return true;
  }
  const json* points = fields.member(document, "", "points", true);
  if (points == nullptr || !fields.points(*points, "points", curve.points)) return false;
  curve.closed = false;
  if (const json* closed = fields.member(document, "", "closed", false)) {
    if (!fields.boolean(*closed, "closed", curve.closed)) return false;
  }
  if (!toLps(document, "", fields, curve)) return false;
  if (curve.points.rows() == 0) {
    fields.error("points", "no points");
    return false;
  }
  for (Eigen::Index k = 0; k < curve.points.rows(); ++k)
    curve.point_wheres.push_back(indexPath("points", static_cast<std::size_t>(k)));
  return true;
}

}  // namespace

bool readCurve(const std::filesystem::path& path, Curve& curve, Diagnostics& diagnostics,
               const std::string& display_name, int markup_index) {
  const std::string file = display_name.empty() ? path.string() : display_name;
  if (isDelimitedCurveFile(path)) return readDelimitedCurve(path, file, curve, diagnostics);
  try {
    const std::optional<std::string> text = readInputText(path, file, "a curve file", diagnostics);
    if (!text) return false;
    const auto document = parseJson(*text, file, diagnostics);
    const std::string extension = asciiLowercase(path.extension().string());
    if (!document && extension != ".json" && !nlohmann::json::accept(*text)) {
      // A ".dat" or ".xyz" file of numbers read as JSON says only "malformed JSON".
      diagnostics.error(file, "",
                        "read as JSON, " +
                            (extension.empty() ? std::string("the file having no extension")
                                               : "its extension \"" + path.extension().string() +
                                                     "\" being none of the text curve formats'") +
                            " (.csv, .txt, .fcsv)");
    }
    if (!document) return false;
    JsonFields fields(file, diagnostics);
    Curve result;
    const bool ok = document->is_object() && document->contains("markups")
                        ? readMarkups(*document, fields, markup_index, result)
                        : readPointList(*document, fields, result);
    if (ok) curve = std::move(result);
    return ok;
  } catch (const std::exception& e) {  // e.g. std::bad_alloc; the contract is "never throws"
    diagnostics.error(file, "", std::string("cannot be read: ") + e.what());
  }
  return false;
}

std::string otherFrameQuestion(const Curve* source) {
  if (source == nullptr) return "are they in RAS? (points inline in the file are read as LPS)";
  if (source->read_as_ras)
    return "the file was read as RAS; are they in LPS? (" + source->other_frame_syntax + ")";
  return "are they in RAS? (" + source->other_frame_syntax + ")";
}

// Throws std::invalid_argument for a matrix that is not #P by 3 or holds a non-finite
// value (JSON has no NaN), std::runtime_error on I/O failure.
void writePointList(const std::filesystem::path& path, const Eigen::MatrixXd& points, bool closed) {
  if (points.cols() != 3 && points.rows() != 0)
    throw std::invalid_argument(path.string() + ": points must have 3 columns");
  if (!points.allFinite()) throw std::invalid_argument(path.string() + ": points must be finite");
  // One point per line keeps the files readable and diffable; nlohmann prints the
  // shortest text that reads back to the same double.
  std::string out =
      "{\n  \"closed\": " + std::string(closed ? "true" : "false") + ",\n  \"points\": [";
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    out += i == 0 ? "\n    [" : ",\n    [";
    for (int k = 0; k < 3; ++k) {
      if (k > 0) out += ", ";
      out += json(points(i, k)).dump();
    }
    out += "]";
  }
  out += points.rows() > 0 ? "\n  ]\n}\n" : "]\n}\n";
  writeFileAtomically(path, out);
}

}  // namespace chordfit
