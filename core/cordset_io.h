// CordSet JSON (docs/case-format.md, "Cord set file"):
//   {"format": "chordfit-cordset", "version": 1, "tips": [...], "cords": [...]}
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/cordset.h"
#include "core/diagnostics.h"
#include "core/valve_mesh.h"

namespace chordfit {

class JsonFields;

constexpr int kCordSetFormatVersion = 1;

// The shortest and longest rest length a cord set may hold, mm (cordset_io.cpp says why:
// chordae are 10-40 mm, make-case's ruptured cords ten times that).
constexpr double kMinCordRestLengthMm = 1.0;
constexpr double kMaxCordRestLengthMm = 1000.0;
// The largest cord compliance a cord set may hold, mm/N (cordset_io.cpp says why).
constexpr double kMaxCordComplianceMmPerN = 10.0;

// Reads a cord set file. Tip references are checked against the file's own tips; vertex
// references need the mesh and are checked by checkCordVertices. Never throws on bad input.
bool readCordSet(const std::filesystem::path& path, const std::string& file, CordSet& set,
                 Diagnostics& diagnostics);

// Reads a "tips" array ([{"name", "position", "closed_position"?}, ...]) at `where`.
bool readTips(const nlohmann::json& array, const std::string& where, JsonFields& fields,
              std::vector<PmTip>& tips);

// The "tips" array as written in cord set and pm_tips files.
nlohmann::json tipsJson(const std::vector<PmTip>& tips);

// Reports cords whose vertex is not a vertex of `mesh`, or whose insertion lies on its annulus
// ring (cordOnRingProblem).
bool checkCordVertices(const CordSet& set, const ValveMesh& mesh, const std::string& file,
                       Diagnostics& diagnostics);

// Writes atomically. With a mesh, each cord also gets its "group" (leaflet/tip) for readers.
void writeCordSet(const std::filesystem::path& path, const CordSet& set,
                  const ValveMesh* mesh = nullptr);

}  // namespace chordfit
