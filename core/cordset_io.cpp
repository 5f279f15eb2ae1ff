#include "core/cordset_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>
#include <tuple>
#include <utility>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/json_fields.h"
#include "core/quoted_text.h"

namespace chordfit {

namespace {

using nlohmann::json;

json vec3Json(const Eigen::Vector3d& p) { return json::array({p.x(), p.y(), p.z()}); }

// "point": {"vertices": [i, j, k], "weights": [a, b, c]}; `vertex` becomes the vertex of
// largest weight unless the file names one.
bool readCordPoint(const json& value, const std::string& where, JsonFields& fields, Cord& cord) {
  // The keys writeCordSet writes; any other is named, with the key it may have meant, instead
  // of being dropped (a misspelt "weights" would only read as missing).
  const bool keys_known = fields.knownKeys(value, where, {"vertices", "weights"});
  const json* vertices = fields.member(value, where, "vertices", true);
  const json* weights = fields.member(value, where, "weights", true);
  if (vertices == nullptr || weights == nullptr) return false;
  Eigen::VectorXi v;
  Eigen::Vector3d b;
  bool ok = fields.integers(*vertices, fieldPath(where, "vertices"), v);
  ok &= fields.vec3(*weights, fieldPath(where, "weights"), b);
  if (!ok) return false;
  if (v.size() != 3) {
    fields.error(fieldPath(where, "vertices"),
                 "expected 3 vertex indices, got " + std::to_string(v.size()));
    return false;
  }
  CordPoint p;
  for (int m = 0; m < 3; ++m) p.vertices[m] = v(m);
  p.weights = b;
  if (!b.allFinite() || b.minCoeff() < 0.0 || std::abs(b.sum() - 1.0) > 1e-9) {
    fields.error(fieldPath(where, "weights"), "weights must be >= 0 and sum to 1");
    return false;
  }
  Eigen::Index largest = 0;
  b.maxCoeff(&largest);
  cord.vertex = p.vertices[largest];
  cord.point = p;
  return keys_known;
}

// Bounds of a cord's values: beyond them (1e308 was accepted) the closure diverges, exit 3,
// without naming the cord. Chordae are 10-40 mm long on valves spanning 30-60 mm, and
// make-case models a ruptured cord as ten times its length (truth/cords.json of the flail
// cases: up to ~300 mm), so a rest length above 1000 mm is a typo or a unit slip. Below 1 mm
// (1e-300 was accepted) a cord would pin its insertion to the PM tip, which lies 15 mm or more
// below the leaflets, and a seed that small turns every scale (rest / seed) into nonsense; it
// is a unit slip (metres) or a typo. The shortest of the 450,000 rest lengths in the 940 cord
// sets on the development machine (bundled, benchmark, fitted) is 15.6 mm, and the fit's
// default lower scale bound 0.7 keeps such a cord above 10 mm. A real
// chord (E ~50 MPa, 0.5 mm², 20 mm: L / EA = 0.8 mm/N) has a compliance near 1 mm/N and the
// bundled cases use 0 (inextensible); at 10 mm/N (kMaxCordComplianceMmPerN) a systolic load of
// ~1 N would stretch a cord by a centimetre.
constexpr const char* kRestLengthWhy =
    "chordae are 10-40 mm long, a ruptured one in make-case ten times that";

// Whether `value`, read from the field `where`, is at most `maximum`; else reports
// "must be at most <maximum> <unit> (<why>), got <value>" there.
bool atMost(double value, double maximum, const char* unit, const char* why,
            const std::string& where, JsonFields& fields) {
  if (value <= maximum) return true;
  std::ostringstream text;
  text << "must be at most " << maximum << " " << unit << " (" << why << "), got " << value;
  fields.error(where, text.str());
  return false;
}

// A rest length read from `where` within [kMinCordRestLengthMm, kMaxCordRestLengthMm].
bool restLengthInRange(double value, const std::string& where, JsonFields& fields) {
  if (value < kMinCordRestLengthMm) {
    std::ostringstream text;
    text << "must be at least " << kMinCordRestLengthMm << " mm (" << kRestLengthWhy << "), got "
         << value;
    fields.error(where, text.str());
    return false;
  }
  return atMost(value, kMaxCordRestLengthMm, "mm", kRestLengthWhy, where, fields);
}

bool readCord(const json& value, const std::string& where, int tip_count, JsonFields& fields,
              Cord& cord) {
  // The keys writeCordSet writes (group and scale only for readers; docs/case-format.md): a
  // misspelt optional one ("compliance") would otherwise be dropped without a word.
  const bool keys_known =
      fields.knownKeys(value, where,
                       {"tip", "vertex", "point", "kind", "group", "seed_rest_length_mm",
                        "rest_length_mm", "scale", "compliance_mm_per_N", "provenance", "locked"});
  bool ok = true;
  if (const json* tip = fields.member(value, where, "tip", true)) {
    ok &= fields.integer(*tip, fieldPath(where, "tip"), cord.tip);
    if (ok && (cord.tip < 0 || cord.tip >= tip_count)) {
      fields.error(fieldPath(where, "tip"), "tip " + std::to_string(cord.tip) +
                                                " does not exist (the file has " +
                                                std::to_string(tip_count) + " tips)");
      ok = false;
    }
  } else {
    ok = false;
  }
  const json* point = fields.member(value, where, "point", false);
  if (point != nullptr) ok &= readCordPoint(*point, fieldPath(where, "point"), fields, cord);
  if (const json* vertex = fields.member(value, where, "vertex", point == nullptr)) {
    int v = 0;
    if (fields.integer(*vertex, fieldPath(where, "vertex"), v)) {
      if (cord.point && std::find(cord.point->vertices.begin(), cord.point->vertices.end(), v) ==
                            cord.point->vertices.end()) {
        fields.error(fieldPath(where, "vertex"),
                     "vertex " + std::to_string(v) + " is not one of the point's vertices");
        ok = false;
      }
      cord.vertex = v;
    } else {
      ok = false;
    }
  } else if (point == nullptr) {
    ok = false;
  }
  if (const json* kind = fields.member(value, where, "kind", false)) {
    std::string text;
    if (fields.text(*kind, fieldPath(where, "kind"), text)) {
      if (auto parsed = parseCordKind(text)) {
        cord.kind = *parsed;
      } else {
        fields.error(fieldPath(where, "kind"), quotedText(text) + " is not primary or secondary");
        ok = false;
      }
    } else {
      ok = false;
    }
  }
  if (const json* rest = fields.member(value, where, "rest_length_mm", true)) {
    ok &= fields.number(*rest, fieldPath(where, "rest_length_mm"), cord.rest_length);
    ok = ok && restLengthInRange(cord.rest_length, fieldPath(where, "rest_length_mm"), fields);
  } else {
    ok = false;
  }
  cord.seed_rest_length = cord.rest_length;
  if (const json* seed = fields.member(value, where, "seed_rest_length_mm", false)) {
    ok &= fields.number(*seed, fieldPath(where, "seed_rest_length_mm"), cord.seed_rest_length);
    ok = ok &&
         restLengthInRange(cord.seed_rest_length, fieldPath(where, "seed_rest_length_mm"), fields);
  }
  if (const json* compliance = fields.member(value, where, "compliance_mm_per_N", false)) {
    ok &= fields.number(*compliance, fieldPath(where, "compliance_mm_per_N"), cord.compliance);
    if (ok && cord.compliance < 0.0) {
      fields.error(fieldPath(where, "compliance_mm_per_N"), "compliance must be >= 0");
      ok = false;
    }
    ok = ok && atMost(cord.compliance, kMaxCordComplianceMmPerN, "mm/N",
                      "a real chord is near 1 mm/N; 0 is inextensible",
                      fieldPath(where, "compliance_mm_per_N"), fields);
  }
  // A hand-written cord set without provenance is the user's: manual.
  cord.provenance = Provenance::kManual;
  if (const json* provenance = fields.member(value, where, "provenance", false)) {
    std::string text;
    if (fields.text(*provenance, fieldPath(where, "provenance"), text)) {
      if (auto parsed = parseProvenance(text)) {
        cord.provenance = *parsed;
      } else {
        fields.error(fieldPath(where, "provenance"),
                     quotedText(text) + " is not heuristic, manual or fitted");
        ok = false;
      }
    } else {
      ok = false;
    }
  }
  if (const json* locked = fields.member(value, where, "locked", false)) {
    ok &= fields.boolean(*locked, fieldPath(where, "locked"), cord.locked);
  }
  return ok && keys_known;
}

// Each tip's name once: tips are found by name (edit-cords --move-tip) and name the cord groups
// ("anterior/anterolateral"), so two tips of one name merged their groups and --move-tip moved
// the later one without a word. An unnamed tip is called "tip<index>" (readTips).
bool tipNamesDistinct(const json& array, const std::string& where, const std::vector<PmTip>& tips,
                      JsonFields& fields) {
  bool ok = true;
  for (std::size_t i = 1; i < tips.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (tips[j].name != tips[i].name) continue;
      const std::string earlier = array[j].contains("name") ? fieldPath(indexPath(where, j), "name")
                                                            : indexPath(where, j) + " (unnamed)";
      if (array[i].contains("name")) {
        fields.error(fieldPath(indexPath(where, i), "name"),
                     quotedText(tips[i].name) + " repeats " + earlier +
                         ": each tip needs a name of its own");
      } else {
        fields.error(indexPath(where, i), "unnamed, it is called " + quotedText(tips[i].name) +
                                              ", which " + earlier +
                                              " gives: each tip needs a name of its own");
      }
      ok = false;
      break;
    }
  }
  return ok;
}

}  // namespace

bool readTips(const json& array, const std::string& where, JsonFields& fields,
              std::vector<PmTip>& tips) {
  if (!array.is_array()) {
    fields.typeError(where, "an array of tips", array);
    return false;
  }
  bool ok = true;
  tips.clear();
  for (std::size_t i = 0; i < array.size(); ++i) {
    const std::string at = indexPath(where, i);
    // The keys tipsJson writes: a misspelt "closed_position" would otherwise leave the tip
    // static without a word.
    ok &= fields.knownKeys(array[i], at, {"name", "position", "closed_position"});
    PmTip tip;
    tip.name = "tip" + std::to_string(i);
    if (const json* name = fields.member(array[i], at, "name", false)) {
      ok &= fields.text(*name, fieldPath(at, "name"), tip.name);
    }
    if (const json* position = fields.member(array[i], at, "position", true)) {
      ok &= fields.vec3(*position, fieldPath(at, "position"), tip.position);
    } else {
      ok = false;
    }
    if (const json* closed = fields.member(array[i], at, "closed_position", false)) {
      Eigen::Vector3d p;
      if (fields.vec3(*closed, fieldPath(at, "closed_position"), p)) {
        tip.closed_position = p;
      } else {
        ok = false;
      }
    }
    tips.push_back(tip);
  }
  return ok && tipNamesDistinct(array, where, tips, fields);
}

bool readCordSet(const std::filesystem::path& path, const std::string& file, CordSet& set,
                 Diagnostics& diagnostics) {
  const std::optional<json> document = loadJsonFile(path, file, diagnostics);
  if (!document) return false;
  JsonFields fields(file, diagnostics);
  if (!document->is_object()) {  // once, not once per key looked up
    fields.typeError("(top level)", "an object", *document);
    return false;
  }
  bool ok = true;
  if (const json* format = fields.member(*document, "", "format", false)) {
    std::string text;
    if (fields.text(*format, "format", text) && text != "chordfit-cordset") {
      fields.error("format", quotedText(text) + " is not a chordfit-cordset file");
      ok = false;
    }
  }
  if (const json* version = fields.member(*document, "", "version", true)) {
    int v = 0;
    if (fields.integer(*version, "version", v) && v != kCordSetFormatVersion) {
      fields.error("version", "unsupported format version " + std::to_string(v) +
                                  " (this build reads version " +
                                  std::to_string(kCordSetFormatVersion) + ")");
      return false;
    }
  } else {
    return false;
  }
  set = CordSet{};
  if (const json* tips = fields.member(*document, "", "tips", true)) {
    ok &= readTips(*tips, "tips", fields, set.tips);
  } else {
    ok = false;
  }
  const json* cords = fields.member(*document, "", "cords", true);
  if (cords == nullptr) return false;
  if (!cords->is_array()) {
    fields.typeError("cords", "an array of cords", *cords);
    return false;
  }
  for (std::size_t i = 0; i < cords->size(); ++i) {
    Cord cord;
    if (readCord((*cords)[i], indexPath("cords", i), static_cast<int>(set.tips.size()), fields,
                 cord)) {
      set.cords.push_back(cord);
    } else {
      ok = false;
    }
  }
  // A cord given twice (same tip, same insertion) pulls twice as hard: a copy-paste slip the
  // closure would not show (30 copies of each cord took a case's AvgD from 3.41 to 5.30 mm).
  if (ok) {
    constexpr int kNamed = 3;
    int repeats = 0;
    // The insertion: its point's vertices and weights, or the vertex alone (cord.vertex is
    // the point's heaviest vertex, so it adds nothing to the key).
    std::map<std::tuple<int, std::array<int, 3>, std::array<double, 3>>, std::size_t> seen;
    for (std::size_t k = 0; k < set.cords.size(); ++k) {
      const Cord& cord = set.cords[k];
      std::array<int, 3> vertices{cord.vertex, -1, -1};
      std::array<double, 3> weights{1.0, 0.0, 0.0};
      if (cord.point) {
        vertices = cord.point->vertices;
        weights = {cord.point->weights(0), cord.point->weights(1), cord.point->weights(2)};
      }
      const auto [it, inserted] = seen.emplace(std::make_tuple(cord.tip, vertices, weights), k);
      if (!inserted && ++repeats <= kNamed)
        fields.error(indexPath("cords", k),
                     "repeats " + indexPath("cords", it->second) +
                         " (the same tip and insertion): a cord given twice pulls twice as hard");
    }
    if (repeats > kNamed)
      fields.error("cords", std::to_string(repeats - kNamed) + " more cords repeat earlier ones (" +
                                std::to_string(repeats) + " of " +
                                std::to_string(set.cords.size()) + ")");
    ok = repeats == 0;
  }

  return ok;
}

bool checkCordVertices(const CordSet& set, const ValveMesh& mesh, const std::string& file,
                       Diagnostics& diagnostics) {
  const int vertex_count = static_cast<int>(mesh.V.rows());
  // A cord set made for another mesh (a make-case truth/cords.json, on the finer truth mesh)
  // has most of its cords beyond this one: the first few are named, then one line says so,
  // instead of one line per cord and point.
  constexpr int kNamedCords = 3;
  int bad_cords = 0;
  for (std::size_t i = 0; i < set.cords.size(); ++i) {
    const Cord& cord = set.cords[i];
    std::vector<std::pair<std::string, std::string>> problems;  // field, problem
    if (cord.vertex < 0 || cord.vertex >= vertex_count)
      problems.emplace_back(".vertex", "vertex " + std::to_string(cord.vertex) +
                                           " does not exist (mesh has " +
                                           std::to_string(vertex_count) + " vertices)");
    if (cord.point) {
      const std::string problem = cordPointProblem(*cord.point, vertex_count);
      if (!problem.empty()) problems.emplace_back(".point", problem);
    }
    if (problems.empty()) {
      const std::string problem = cordOnRingProblem(cord, mesh.annulus);
      if (!problem.empty()) problems.emplace_back(cord.point ? ".point" : ".vertex", problem);
    }
    if (problems.empty()) continue;
    if (++bad_cords > kNamedCords) continue;
    for (const auto& [field, problem] : problems)
      diagnostics.error(file, indexPath("cords", i) + field, problem);
  }
  if (bad_cords > kNamedCords)
    diagnostics.error(file, "cords",
                      std::to_string(bad_cords - kNamedCords) + " more cords (" +
                          std::to_string(bad_cords) + " of " + std::to_string(set.cords.size()) +
                          ") attach beyond the mesh's " + std::to_string(vertex_count) +
                          " vertices or on its annulus ring: was this cord set made for another "
                          "mesh? (a make-case "
                          "truth/cords.json belongs to truth/case)");
  return bad_cords == 0;
}

json tipsJson(const std::vector<PmTip>& tips) {
  json list = json::array();
  for (const PmTip& tip : tips) {
    json t = {{"name", tip.name}, {"position", vec3Json(tip.position)}};
    if (tip.closed_position) t["closed_position"] = vec3Json(*tip.closed_position);
    list.push_back(t);
  }
  return list;
}

void writeCordSet(const std::filesystem::path& path, const CordSet& set, const ValveMesh* mesh) {
  json cords = json::array();
  for (const Cord& cord : set.cords) {
    json c = {{"tip", cord.tip}, {"vertex", cord.vertex}, {"kind", toString(cord.kind)}};
    if (cord.point) {
      const CordPoint& p = *cord.point;
      c["point"] = {{"vertices", {p.vertices[0], p.vertices[1], p.vertices[2]}},
                    {"weights", vec3Json(p.weights)}};
    }
    if (mesh != nullptr) c["group"] = groupName(cord, mesh->leaflet, mesh->leaflet_names, set.tips);
    c["seed_rest_length_mm"] = cord.seed_rest_length;
    c["rest_length_mm"] = cord.rest_length;
    // Only for readers (the rest length is the value): rounded to 12 decimals, so that a
    // scale fitted to its bound reads 0.7, not the 0.6999999999999998 of rest / seed.
    c["scale"] = std::round(cord.scale() * 1e12) / 1e12;
    c["compliance_mm_per_N"] = cord.compliance;
    c["provenance"] = toString(cord.provenance);
    c["locked"] = cord.locked;
    cords.push_back(c);
  }
  const json document = {{"format", "chordfit-cordset"},
                         {"version", kCordSetFormatVersion},
                         {"tips", tipsJson(set.tips)},
                         {"cords", cords}};
  writeFileAtomically(path, document.dump(2) + "\n");
}

}  // namespace chordfit
