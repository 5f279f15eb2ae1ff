#include "core/case_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/case_extent.h"
#include "core/cordset_io.h"
#include "core/curve_io.h"
#include "core/joined.h"
#include "core/json_fields.h"
#include "core/mesh_checks.h"
#include "core/mesh_io.h"
#include "core/quoted_text.h"

namespace chordfit {

namespace {

// A C0 control character or DEL: what a name shown on one line of a summary or table must not
// hold (leaflet names, the case's name).
bool isControlByte(char ch) { return static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f; }

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kCaseFile = "case.json";

// A side file named by a string field of case.json; resolved relative to the case directory.
struct SideFile {
  fs::path path;
  std::string name;  // as written in case.json, used in messages
};

// The directory a relative file name is looked for in, as the user can find it again: absolute,
// without "." steps or a trailing separator (the case directory is often given as ".").
std::string searchedDirectory(const fs::path& dir) {
  std::error_code ec;
  fs::path shown = fs::absolute(dir.empty() ? fs::path(".") : dir, ec).lexically_normal();
  if (shown.has_parent_path() && shown.filename().empty()) shown = shown.parent_path();
  return ec ? dir.string() : shown.string();
}

// Whether the file `name` that the field `where` gives can be read, looked for in `dir`. An
// empty name, a missing file or a path that is no readable file (a directory, a device) is the
// field's mistake, reported there with the name; a missing one also with the directory searched
// ("error: nope.ply: file not found" named neither the field nor where it was looked for). An
// empty name used to parse the case directory itself as JSON, and a device to be read forever.
bool fileFieldUsable(const std::string& name, const fs::path& dir, const std::string& where,
                     JsonFields& fields) {
  const fs::path path = dir / name;
  std::error_code ec;
  const bool named_entry_exists = fs::exists(fs::symlink_status(path, ec));
  std::string problem;
  if (name.empty()) {
    problem = "no file given (an empty file name)";
  } else if (!named_entry_exists && ec && ec != std::errc::no_such_file_or_directory) {
    // A directory on the way the user may not search is not a missing file.
    problem = quotedText(name, std::string::npos) + ": cannot be looked up (" + ec.message() + ")";
  } else if (!named_entry_exists) {
    problem = quotedText(name, std::string::npos) + ": file not found";
    if (fs::path(name).is_relative()) problem += " in " + searchedDirectory(dir);
  } else if (!fs::exists(path, ec) && !ec) {
    problem = quotedText(name, std::string::npos) +
              " is a symbolic link to nothing (its target is missing)";
  } else if (const std::string unusable = inputFileProblem(path); !unusable.empty()) {
    problem = quotedText(name, std::string::npos) + " " + unusable;
  }
  if (problem.empty()) return true;
  fields.error(where, problem);
  return false;
}

std::optional<SideFile> sideFile(const json& object, const std::string& where,
                                 const std::string& key, bool required, const fs::path& dir,
                                 JsonFields& fields) {
  const json* value = fields.member(object, where, key, required);
  if (value == nullptr) return std::nullopt;
  std::string name;
  if (!fields.text(*value, fieldPath(where, key), name) ||
      !fileFieldUsable(name, dir, fieldPath(where, key), fields))
    return std::nullopt;
  return SideFile{dir / name, name};
}

// Side files hold one array, either bare or under `key`: [..] or {"key": [..]}. Loads the
// file and hands the array and the file's field reporter to `read`; false when the file
// cannot be read, parsed or has no such array.
template <typename ReadArray>
bool readSideArray(const SideFile& file, const std::string& key, Diagnostics& diagnostics,
                   ReadArray read) {
  const auto document = loadJsonFile(file.path, file.name, diagnostics);
  if (!document) return false;
  JsonFields fields(file.name, diagnostics);
  const json* array = document->is_array() ? &*document : fields.member(*document, "", key, true);
  return array != nullptr && read(*array, fields);
}

// "\"anterior\", \"posterior\"": the case's leaflet names as JSON strings.
std::string quotedNames(const std::vector<std::string>& names) {
  std::vector<std::string> quoted;
  for (const std::string& name : names) quoted.push_back(json(name).dump());
  return joined(quoted, ", ");
}

// ": labels run from 0 to 1, one per leaflet name in case.json (leaflets.names or its default:
// "anterior", "posterior")": said beside a label or tracing leaflet that is not a leaflet, as
// the names may be what changed.
std::string leafletNumbersNote(const std::string& what, const std::vector<std::string>& names) {
  return ": " + what + " run from 0 to " + std::to_string(names.size() - 1) +
         ", one per leaflet name in case.json (leaflets.names or its default: " +
         quotedNames(names) + ")";
}

// One leaflet label per mesh vertex, each naming one of the case's leaflets.
bool readLabelArray(const json& labels, JsonFields& fields, ValveCase& c) {
  if (!fields.integers(labels, "labels", c.mesh.leaflet)) return false;
  if (c.mesh.leaflet.size() != c.mesh.V.rows()) {
    fields.error("labels", std::to_string(c.mesh.leaflet.size()) +
                               " leaflet labels for a mesh of " + std::to_string(c.mesh.V.rows()) +
                               " vertices");
    return false;
  }
  const int leaflet_count = static_cast<int>(c.mesh.leaflet_names.size());
  std::vector<int> vertices_per_leaflet(leaflet_count, 0);
  for (Eigen::Index v = 0; v < c.mesh.leaflet.size(); ++v) {
    if (c.mesh.leaflet(v) < 0 || c.mesh.leaflet(v) >= leaflet_count) {
      fields.error(indexPath("labels", v), "label " + std::to_string(c.mesh.leaflet(v)) +
                                               " is not a leaflet" +
                                               leafletNumbersNote("labels", c.mesh.leaflet_names));
      return false;
    }
    ++vertices_per_leaflet[c.mesh.leaflet(v)];
  }
  // A leaflet without vertices has no cords, segments or surface: own-leaflet distances to
  // it are undefined (the fit measured tracing points against nothing).
  for (int l = 0; l < leaflet_count; ++l) {
    if (vertices_per_leaflet[l] == 0) {
      fields.error("labels", "no vertex is labelled " + std::to_string(l) + " (" +
                                 c.mesh.leaflet_names[l] + "): every leaflet needs its vertices");
      return false;
    }
  }
  return true;
}

bool readLabels(const SideFile& file, ValveCase& c, Diagnostics& diagnostics) {
  return readSideArray(file, "labels", diagnostics, [&](const json& labels, JsonFields& fields) {
    return readLabelArray(labels, fields, c);
  });
}

// Regional tissue: one stiffness factor per mesh vertex, each positive and finite (a factor of
// 0 would be a hole in the leaflet, not a tissue).
bool readTissue(const SideFile& file, ValveCase& c, Diagnostics& diagnostics) {
  return readSideArray(file, "stiffness", diagnostics, [&](const json& array, JsonFields& fields) {
    if (!array.is_array()) {
      fields.typeError("stiffness", "an array of numbers", array);
      return false;
    }
    if (static_cast<Eigen::Index>(array.size()) != c.mesh.V.rows()) {
      fields.error("stiffness", std::to_string(array.size()) + " stiffness factors for a mesh of " +
                                    std::to_string(c.mesh.V.rows()) + " vertices");
      return false;
    }
    Eigen::VectorXd factors(array.size());
    for (std::size_t v = 0; v < array.size(); ++v) {
      const std::string where = indexPath("stiffness", v);
      if (!fields.number(array[v], where, factors(v))) return false;
      if (!(factors(v) > 0.0) || !std::isfinite(factors(v)) || factors(v) > 1e3) {
        fields.error(where, "stiffness factor must be in (0, 1000], got " + array[v].dump());
        return false;
      }
    }
    c.tissue_stiffness = factors;
    return true;
  });
}

bool readRing(const SideFile& file, ValveCase& c, Diagnostics& diagnostics) {
  return readSideArray(file, "vertices", diagnostics, [&](const json& ring, JsonFields& fields) {
    return fields.integers(ring, "vertices", c.mesh.annulus);
  });
}

// Leaflet of a tracing: a leaflet name, a label number, or null / absent (unknown).
bool readTracingLeaflet(const json& value, const std::string& where,
                        const std::vector<std::string>& names, JsonFields& fields, int& leaflet) {
  if (value.is_string()) {
    const std::string name = value.get<std::string>();
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i] == name) {
        leaflet = static_cast<int>(i);
        return true;
      }
    }
    fields.error(where, quotedText(name) + " is not a leaflet name of this case: case.json names " +
                            quotedNames(names) + " (leaflets.names or its default)");
    return false;
  }
  if (!fields.integer(value, where, leaflet)) return false;
  if (leaflet < 0 || leaflet >= static_cast<int>(names.size())) {
    fields.error(where, "leaflet " + std::to_string(leaflet) + " does not exist" +
                            leafletNumbersNote("leaflets", names));
    return false;
  }
  return true;
}

// A tracing is drawn on its image plane; its points must lie on it. The metrics and the fit
// cut the closed mesh by the plane (section prolapse, section figure), so points off it would
// be compared with a section they were not drawn on. The tolerance allows for rounding and an
// image slice's thickness.
constexpr double kTracingPlaneToleranceMm = 1.0;

// A tracing whose points all lie within this of its first one is a point, not a polyline:
// no image resolves 1 µm. Repeated points inside a tracing are harmless (each is measured as
// a point, and the section residual's distance to a zero-length segment is the distance to
// its point), so only the tracing as a whole is checked.
constexpr double kTracingMinExtentMm = 1e-3;

// "" when the tracing's points span more than kTracingMinExtentMm; else the problem, naming
// `source` (the curve file) when the points came from one.
std::string zeroLengthTracingProblem(const Eigen::MatrixXd& points, const std::string& source) {
  for (Eigen::Index k = 1; k < points.rows(); ++k)
    if ((points.row(k) - points.row(0)).norm() > kTracingMinExtentMm) return "";
  char what[240];
  std::snprintf(what, sizeof what,
                "the tracing has no length: its %ld points all lie at (%.6g, %.6g, %.6g) (within "
                "%g mm of the first); a tracing needs at least 2 distinct points",
                static_cast<long>(points.rows()), points(0, 0), points(0, 1), points(0, 2),
                kTracingMinExtentMm);
  return (source.empty() ? "" : source + ": ") + what;
}

// `source`: the curve file the points came from (how it was read decides the advice), or
// nullptr for points inline in the tracings file (LPS).
bool checkTracingOnItsPlane(const Tracing& tracing, const std::string& where, JsonFields& fields,
                            const Curve* source) {
  int off = 0;
  double farthest = 0.0;
  Eigen::Index first = -1;
  for (Eigen::Index k = 0; k < tracing.points.rows(); ++k) {
    const double distance = std::abs(
        tracing.plane_normal.dot(tracing.points.row(k).transpose() - tracing.plane_origin));
    if (distance <= kTracingPlaneToleranceMm) continue;
    if (off++ == 0) first = k;
    farthest = std::max(farthest, distance);
  }
  if (off == 0) return true;
  // Points exported in RAS and read as LPS (a curve file without its coordinate system) lie
  // on the plane once x and y are negated: say so, it is the common slip.
  bool on_plane_in_ras = true;
  for (Eigen::Index k = 0; k < tracing.points.rows() && on_plane_in_ras; ++k) {
    const Eigen::Vector3d ras(-tracing.points(k, 0), -tracing.points(k, 1), tracing.points(k, 2));
    on_plane_in_ras =
        std::abs(tracing.plane_normal.dot(ras - tracing.plane_origin)) <= kTracingPlaneToleranceMm;
  }
  const std::string advice =
      on_plane_in_ras ? "with x and y negated they lie on it: " + otherFrameQuestion(source)
                      : "the plane or the points are wrong";
  char what[200];
  std::snprintf(what, sizeof what,
                "%d of %d points lie off the tracing's plane (first: point %ld; farthest %.3g mm; "
                "at most %g mm): ",
                off, static_cast<int>(tracing.points.rows()), static_cast<long>(first), farthest,
                kTracingPlaneToleranceMm);
  fields.error(where, what + advice);
  return false;
}

// `mesh_V`: the valve the points must lie within reach of (checkPointsNearValve; empty: not
// checked, as when the mesh did not read).
bool readTracing(const json& entry, const std::string& where, const fs::path& dir,
                 const std::vector<std::string>& leaflet_names, const Eigen::MatrixXd& mesh_V,
                 JsonFields& fields, Tracing& tracing) {
  // The keys writeCase writes, and "file": a misspelt optional "leaflet" would otherwise
  // leave the tracing unlabelled, measured to the whole mesh, without a word.
  bool ok = fields.knownKeys(entry, where, {"plane", "leaflet", "points", "file"});
  if (const json* plane = fields.member(entry, where, "plane", true)) {
    const std::string at = fieldPath(where, "plane");
    ok &= fields.knownKeys(*plane, at, {"origin", "normal"});
    if (const json* origin = fields.member(*plane, at, "origin", true)) {
      ok &= fields.vec3(*origin, fieldPath(at, "origin"), tracing.plane_origin);
    } else {
      ok = false;
    }
    if (const json* normal = fields.member(*plane, at, "normal", true)) {
      if (fields.vec3(*normal, fieldPath(at, "normal"), tracing.plane_normal)) {
        // Finite components can still have an infinite norm ([1e308, 1, 0]); normalising that
        // gives a zero normal, on whose "plane" every point lies.
        const double length = tracing.plane_normal.norm();
        if (!(length > 1e-12) || !std::isfinite(length)) {
          fields.error(fieldPath(at, "normal"),
                       length > 1e-12 ? "plane normal is too long to normalise (its length "
                                        "overflows); give a unit vector"
                                      : "plane normal has zero length");
          ok = false;
        } else {
          tracing.plane_normal.normalize();
        }
      } else {
        ok = false;
      }
    } else {
      ok = false;
    }
  } else {
    ok = false;
  }
  if (const json* leaflet = fields.member(entry, where, "leaflet", false)) {
    ok &= readTracingLeaflet(*leaflet, fieldPath(where, "leaflet"), leaflet_names, fields,
                             tracing.leaflet);
  }
  const json* points = fields.member(entry, where, "points", false);
  const json* file = fields.member(entry, where, "file", false);
  if (points != nullptr && file != nullptr) {
    // Which one did the user mean? Reading one would ignore the other without a word.
    fields.error(where, "give \"points\" or \"file\", not both");
    return false;
  }
  Curve curve;       // the file's, when the points come from one
  std::string name;  // that file's name
  if (points != nullptr) {
    ok &= fields.points(*points, fieldPath(where, "points"), tracing.points);
  } else if (file != nullptr) {
    if (fields.text(*file, fieldPath(where, "file"), name) &&
        fileFieldUsable(name, dir, fieldPath(where, "file"), fields) &&
        readCurve(dir / name, curve, fields.diagnostics(), name)) {
      tracing.points = curve.points;
    } else {
      ok = false;
    }
  } else {
    fields.error(where, "a tracing needs \"points\" or \"file\"");
    return false;
  }
  const std::string points_where = fieldPath(where, points != nullptr ? "points" : "file");
  if (ok && tracing.points.rows() < 2) {
    fields.error(points_where, (name.empty() ? "" : name + ": ") +
                                   "a tracing needs at least 2 points, got " +
                                   std::to_string(tracing.points.rows()));
    ok = false;
  }
  if (ok) {
    if (const std::string problem = zeroLengthTracingProblem(tracing.points, name);
        !problem.empty()) {
      fields.error(points_where, problem);
      ok = false;
    }
  }
  if (ok)
    ok =
        checkTracingOnItsPlane(tracing, points_where, fields, points != nullptr ? nullptr : &curve);
  // A point from a curve file is named where it stands in that file ("t.csv: line 4"), not
  // as a point of the tracings file, which has none.
  if (ok)
    ok = points != nullptr ? checkPointsNearValve(mesh_V, tracing.points, fields.file(),
                                                  points_where, fields.diagnostics())
                           : checkCurveNearValve(mesh_V, curve, name, fields.diagnostics());
  return ok;
}

// `mesh_ok`: c.mesh read, so that the points can be checked against it.
bool readTracings(const SideFile& file, const fs::path& dir, bool mesh_ok, ValveCase& c,
                  Diagnostics& diagnostics) {
  const Eigen::MatrixXd no_mesh;
  return readSideArray(file, "tracings", diagnostics, [&](const json& list, JsonFields& fields) {
    if (!list.is_array()) {
      fields.typeError("tracings", "an array of tracings", list);
      return false;
    }
    bool ok = true;
    for (std::size_t i = 0; i < list.size(); ++i) {
      Tracing tracing;
      if (readTracing(list[i], indexPath("tracings", i), dir, c.mesh.leaflet_names,
                      mesh_ok ? c.mesh.V : no_mesh, fields, tracing)) {
        c.tracings.push_back(std::move(tracing));
      } else {
        ok = false;
      }
    }
    return ok;
  });
}

}  // namespace

bool readTracingsFile(const fs::path& path, const std::vector<std::string>& leaflet_names,
                      std::vector<Tracing>& tracings, Diagnostics& diagnostics) {
  ValveCase c;
  c.mesh.leaflet_names = leaflet_names;
  if (!readTracings(SideFile{path, path.string()}, path.parent_path(), false, c, diagnostics)) {
    return false;
  }
  tracings = std::move(c.tracings);
  return true;
}

namespace {

bool readTipsFile(const SideFile& file, ValveCase& c, Diagnostics& diagnostics) {
  return readSideArray(file, "tips", diagnostics, [&](const json& list, JsonFields& fields) {
    std::vector<PmTip> tips;
    if (!readTips(list, "tips", fields, tips)) return false;
    // An empty list read as a case without tips (the heuristic placed them) although the case
    // names a tips file: say so rather than guess which was meant.
    if (tips.empty()) {
      fields.error("tips",
                   "no tips: give at least one, or leave pm_tips out of case.json (the heuristic "
                   "then places the tips)");
      return false;
    }
    c.tips = tips;
    return true;
  });
}

bool readVersion(const json& document, JsonFields& fields) {
  if (const json* format = fields.member(document, "", "format", false)) {
    std::string text;
    if (!fields.text(*format, "format", text)) return false;
    if (text != "chordfit-case") {
      fields.error("format", quotedText(text) + " is not a chordfit-case file");
      return false;
    }
  }
  const json* version = fields.member(document, "", "version", true);
  int v = 0;
  if (version == nullptr || !fields.integer(*version, "version", v)) return false;
  if (v != kCaseFormatVersion) {
    fields.error("version", "unsupported format version " + std::to_string(v) +
                                " (this build reads version " + std::to_string(kCaseFormatVersion) +
                                ")");
    return false;
  }
  return true;
}

// Why `name` cannot name a leaflet, naming the character, or "". A leaflet's name is part of
// its cord groups' names ("anterior/anterolateral"), which edit-cords takes as --group NAME=S:
// a '/' in it made groups that could not be told apart ("a/b" + "c" and "a" + "b/c"); a
// control character (a newline) broke the summary's lines and the groups' names, as in the
// case's name. An '=' is fine: edit-cords splits NAME=S at the last '=', before a number.
std::string leafletNameProblem(const std::string& name) {
  for (const char ch : name) {
    if (isControlByte(ch))
      return "contains a control character (" + shownText(std::string(1, ch)) +
             "): give a name of printable characters";
    if (ch == '/')
      return "contains '/', which joins a cord group's leaflet and tip "
             "(\"anterior/anterolateral\"): edit-cords --group could not tell them apart";
  }
  return "";
}

bool readLeafletNames(const json& leaflets, JsonFields& fields, ValveCase& c) {
  const json* names = fields.member(leaflets, "leaflets", "names", false);
  if (names == nullptr) return true;  // mitral default
  if (!names->is_array() || names->empty()) {
    fields.error("leaflets.names", "expected a non-empty array of leaflet names");
    return false;
  }
  c.mesh.leaflet_names.clear();
  for (std::size_t i = 0; i < names->size(); ++i) {
    std::string name;
    if (!fields.text((*names)[i], indexPath("leaflets.names", i), name)) return false;
    // Names make the cord groups ("anterior/anterolateral") and the tracings' leaflets: a
    // blank or repeated one merged two leaflets into one group.
    if (name.find_first_not_of(" \t") == std::string::npos) {
      fields.error(indexPath("leaflets.names", i), "a leaflet name must not be blank");
      return false;
    }
    if (const std::string problem = leafletNameProblem(name); !problem.empty()) {
      fields.error(indexPath("leaflets.names", i), quotedText(name) + " " + problem);
      return false;
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (c.mesh.leaflet_names[j] == name) {
        fields.error(indexPath("leaflets.names", i),
                     quotedText(name) + " repeats leaflets.names[" + std::to_string(j) + "]");
        return false;
      }
    }
    c.mesh.leaflet_names.push_back(name);
  }
  return true;
}

}  // namespace

bool checkValveMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const std::string& file,
                    Diagnostics& diagnostics) {
  // The span before the per-face checks, whose zero-area tolerance is relative to the bounding
  // box: one vertex at 1e10 mm made every triangle "degenerate" and the outlier went unnamed.
  // With the span wrong the areas are not judged; non-finite coordinates are checkMesh's to
  // name, vertex by vertex.
  const bool span_ok = !V.allFinite() || checkValveSpan(V, file, diagnostics);
  return checkMesh(V, F, file, diagnostics, span_ok) && span_ok;
}

namespace {

// Mesh, labels and annulus: the parts every later check depends on.
bool readValve(const json& document, const fs::path& dir, JsonFields& fields, ValveCase& c) {
  Diagnostics& diagnostics = fields.diagnostics();
  bool ok = true;
  const auto mesh_file = sideFile(document, "", "mesh", true, dir, fields);
  const bool mesh_ok =
      mesh_file && readMesh(mesh_file->path, c.mesh.V, c.mesh.F, diagnostics, mesh_file->name) &&
      checkValveMesh(c.mesh.V, c.mesh.F, mesh_file->name, diagnostics);
  ok &= mesh_ok;

  const json* leaflets = fields.member(document, "", "leaflets", true);
  if (leaflets != nullptr) fields.knownKeys(*leaflets, "leaflets", {"names", "labels"});
  if (leaflets != nullptr && readLeafletNames(*leaflets, fields, c)) {
    const auto labels = sideFile(*leaflets, "leaflets", "labels", true, dir, fields);
    ok &= labels && (!mesh_ok || readLabels(*labels, c, diagnostics));
  } else {
    ok = false;
  }

  const json* annulus = fields.member(document, "", "annulus", true);
  if (annulus == nullptr) return false;
  fields.knownKeys(*annulus, "annulus", {"ring", "closed"});
  const auto ring = sideFile(*annulus, "annulus", "ring", true, dir, fields);
  bool ring_ok = ring && readRing(*ring, c, diagnostics);
  if (ring_ok && mesh_ok) {
    ring_ok = checkAnnulusRing(c.mesh.F, static_cast<int>(c.mesh.V.rows()), c.mesh.annulus,
                               ring->name, "vertices", diagnostics);
  }
  ok &= ring_ok;
  const auto closed = sideFile(*annulus, "annulus", "closed", true, dir, fields);
  Curve closed_curve;
  if (closed && readCurve(closed->path, closed_curve, diagnostics, closed->name)) {
    c.annulus_closed = closed_curve.points;
    // A point far from the valve is the problem to report: the ring's length and shape measured
    // through it would only repeat it ("the closed annulus is inf mm around" for 1e308).
    const bool near_valve =
        !mesh_ok || checkCurveNearValve(c.mesh.V, closed_curve, closed->name, diagnostics);
    ok &= near_valve;
    if (ring_ok && c.annulus_closed.rows() != c.mesh.annulus.size()) {
      diagnostics.error(closed->name, "points",
                        std::to_string(c.annulus_closed.rows()) +
                            " closed-state annulus positions for an annulus ring of " +
                            std::to_string(c.mesh.annulus.size()) + " vertices");
      ok = false;
    } else if (ring_ok && mesh_ok && near_valve) {
      Eigen::MatrixXd open_ring(c.mesh.annulus.size(), 3);
      for (Eigen::Index k = 0; k < c.mesh.annulus.size(); ++k)
        open_ring.row(k) = c.mesh.V.row(c.mesh.annulus(k));
      ok &= checkClosedAnnulus(open_ring, c.annulus_closed, closed->name, diagnostics,
                               closed_curve.point_wheres);
    }
  } else {
    ok = false;
  }
  return ok;
}

bool readOptionalParts(const json& document, const fs::path& dir, JsonFields& fields, bool mesh_ok,
                       ValveCase& c) {
  Diagnostics& diagnostics = fields.diagnostics();
  bool ok = true;
  if (const auto tracings = sideFile(document, "", "tracings", false, dir, fields)) {
    // A tracing's curve file is relative to the file that names it, as every relative name
    // is (case.json's to the case; import-mesh --tracings the same): the tracings file's
    // directory, the case's own when it lies at the top.
    ok &= readTracings(*tracings, tracings->path.parent_path(), mesh_ok, c, diagnostics);
  }
  if (const auto tips = sideFile(document, "", "pm_tips", false, dir, fields)) {
    const bool read = readTipsFile(*tips, c, diagnostics);
    ok &= read;
    if (read && mesh_ok && c.tips)
      ok &= checkTipPlacement(c.mesh, *c.tips, tips->name, diagnostics);
  }
  if (const auto cords = sideFile(document, "", "cords", false, dir, fields)) {
    CordSet set;
    if (readCordSet(cords->path, cords->name, set, diagnostics)) {
      if (mesh_ok) {
        ok &= checkCordVertices(set, c.mesh, cords->name, diagnostics);
        ok &= checkTipPlacement(c.mesh, set.tips, cords->name, diagnostics);
      }
      c.cords = set;
    } else {
      ok = false;
    }
  }
  if (const auto tissue = sideFile(document, "", "tissue_stiffness", false, dir, fields)) {
    ok &= mesh_ok && readTissue(*tissue, c, diagnostics);
  }
  if (const json* simulation = fields.member(document, "", "simulation", false)) {
    if (!simulation->is_object()) {
      fields.typeError("simulation", "an object", *simulation);
      ok = false;
    } else {
      c.simulation_json = simulation->dump();
    }
  }
  return ok;
}

}  // namespace

std::string caseNameProblem(const std::string& name) {
  if (std::any_of(name.begin(), name.end(), isControlByte))
    return "contains a control character (a newline, tab or NUL): give a name of printable "
           "characters";
  if (name.find_first_not_of(' ') == std::string::npos) return "is blank: give the case a name";
  return "";
}

namespace {

// loadCase on a Diagnostics of its own (whose growth says whether the case failed).
std::optional<ValveCase> loadCaseChecked(const fs::path& directory, Diagnostics& diagnostics) {
  const std::size_t problems_before = diagnostics.problems().size();
  std::error_code ec;
  // A loop of links, a name too long, a parent the user may not search: say why (status()
  // without an error code threw them out of the command as an unexpected failure).
  const fs::file_status directory_status = fs::status(directory, ec);
  if (ec && directory_status.type() != fs::file_type::not_found) {
    diagnostics.error(directory.string(), "", "cannot be read (" + ec.message() + ")");
    return std::nullopt;
  }
  if (!fs::is_directory(directory_status)) {
    diagnostics.error(
        directory.string(), "",
        fs::exists(directory_status) ? "not a directory" : "case directory not found");
    return std::nullopt;
  }
  const fs::path case_file = directory / kCaseFile;
  // A link that loops, or a directory the user may not search, is not "not found": say why.
  const fs::file_status case_file_status = fs::status(case_file, ec);
  if (ec && case_file_status.type() != fs::file_type::not_found) {
    diagnostics.error(case_file.string(), "", "cannot be read (" + ec.message() + ")");
    return std::nullopt;
  }
  if (fs::is_symlink(fs::symlink_status(case_file, ec)) && !fs::exists(case_file_status)) {
    diagnostics.error(case_file.string(), "",
                      "is a symbolic link to nothing (a missing target or a loop of links)");
    return std::nullopt;
  }
  // A directory without case.json is not a case at all: say what a case is and how one is
  // made, rather than "case.json: file not found".
  if (!fs::exists(case_file_status)) {
    diagnostics.error(case_file.string(), "",
                      "not found: a case directory holds case.json and the files it names "
                      "(docs/case-format.md; make one with chordfit make-valve, import-mesh or "
                      "make-case)");
    return std::nullopt;
  }
  const auto document = loadJsonFile(case_file, kCaseFile, diagnostics);
  if (!document) return std::nullopt;
  JsonFields fields(kCaseFile, diagnostics);
  if (!document->is_object()) {
    fields.typeError("(top level)", "an object", *document);
    return std::nullopt;
  }
  if (!readVersion(*document, fields)) return std::nullopt;
  // The keys writeCase writes (docs/case-format.md); a misspelt optional one ("tracing") used
  // to read as absent and the case validated without it.
  fields.knownKeys(*document, "",
                   {"format", "version", "name", "mesh", "leaflets", "annulus", "tracings",
                    "pm_tips", "cords", "tissue_stiffness", "simulation"});

  ValveCase c;
  c.name = directory.filename().string();
  if (const json* name = fields.member(*document, "", "name", false)) {
    if (fields.text(*name, "name", c.name)) {
      if (const std::string problem = caseNameProblem(c.name); !problem.empty())
        fields.error("name", problem);
    }
  }
  const bool valve_ok = readValve(*document, directory, fields, c);
  readOptionalParts(*document, directory, fields, c.mesh.V.rows() > 0 && valve_ok, c);
  if (diagnostics.problems().size() != problems_before) return std::nullopt;
  return c;
}

}  // namespace

std::optional<ValveCase> loadCase(const fs::path& directory, Diagnostics& diagnostics) {
  // Its own collector: the caller's may already hold a problem word for word, which would not
  // be added again (Diagnostics reports each once) and so would not show this case's failure.
  Diagnostics own;
  std::optional<ValveCase> loaded = loadCaseChecked(directory, own);
  diagnostics.merge(own);
  return loaded;
}

void writeCase(const fs::path& directory, const ValveCase& c) {
  writePly(directory / "open.ply", c.mesh.V, c.mesh.F);
  std::vector<int> labels(c.mesh.leaflet.data(), c.mesh.leaflet.data() + c.mesh.leaflet.size());
  writeFileAtomically(directory / "leaflets.json", json{{"labels", labels}}.dump() + "\n");
  std::vector<int> ring(c.mesh.annulus.data(), c.mesh.annulus.data() + c.mesh.annulus.size());
  writeFileAtomically(directory / "annulus_ring.json", json{{"vertices", ring}}.dump() + "\n");
  writePointList(directory / "annulus_closed.json", c.annulus_closed, true);

  json document = {{"format", "chordfit-case"},
                   {"version", kCaseFormatVersion},
                   {"mesh", "open.ply"},
                   {"leaflets", {{"names", c.mesh.leaflet_names}, {"labels", "leaflets.json"}}},
                   {"annulus", {{"ring", "annulus_ring.json"}, {"closed", "annulus_closed.json"}}}};
  // A case built without a name is named after its directory when read (an empty "name" is
  // refused: caseNameProblem).
  if (!c.name.empty()) document["name"] = c.name;
  if (!c.tracings.empty()) {
    json list = json::array();
    for (const Tracing& t : c.tracings) {
      json points = json::array();
      for (Eigen::Index i = 0; i < t.points.rows(); ++i) {
        points.push_back({t.points(i, 0), t.points(i, 1), t.points(i, 2)});
      }
      json entry = {{"plane",
                     {{"origin", {t.plane_origin.x(), t.plane_origin.y(), t.plane_origin.z()}},
                      {"normal", {t.plane_normal.x(), t.plane_normal.y(), t.plane_normal.z()}}}},
                    {"points", points}};
      if (t.leaflet >= 0) entry["leaflet"] = c.mesh.leaflet_names.at(t.leaflet);
      list.push_back(entry);
    }
    writeFileAtomically(directory / "tracings.json", json{{"tracings", list}}.dump(1) + "\n");
    document["tracings"] = "tracings.json";
  }
  if (c.tips) {
    writeFileAtomically(directory / "pm_tips.json",
                        json{{"tips", tipsJson(*c.tips)}}.dump(2) + "\n");
    document["pm_tips"] = "pm_tips.json";
  }
  if (c.cords) {
    writeCordSet(directory / "cords.json", *c.cords, &c.mesh);
    document["cords"] = "cords.json";
  }
  if (c.tissue_stiffness.size() > 0) {
    writeTissueFile(directory / "tissue.json", c.tissue_stiffness);
    document["tissue_stiffness"] = "tissue.json";
  }
  if (c.simulation_json != "{}") document["simulation"] = json::parse(c.simulation_json);
  writeFileAtomically(directory / kCaseFile, document.dump(2) + "\n");
}

std::vector<std::string> caseFileNames() {
  return {
      kCaseFile,       "open.ply",     "leaflets.json", "annulus_ring.json", "annulus_closed.json",
      "tracings.json", "pm_tips.json", "cords.json",    "tissue.json"};
}

bool loadTissueFile(const fs::path& path, const std::string& name, ValveCase& valve_case,
                    Diagnostics& diagnostics) {
  return readTissue(SideFile{path, name}, valve_case, diagnostics);
}

void writeTissueFile(const fs::path& path, const Eigen::VectorXd& factors) {
  const std::vector<double> values(factors.data(), factors.data() + factors.size());
  writeFileAtomically(path, json{{"stiffness", values}}.dump() + "\n");
}

}  // namespace chordfit
