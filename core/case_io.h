// Case directories (format v1, docs/case-format.md): case.json plus the files it names.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/case_data.h"
#include "core/diagnostics.h"

namespace chordfit {

constexpr int kCaseFormatVersion = 1;

// Reads and validates a case directory. Reports every problem it can find (missing files,
// malformed JSON, wrong types, unknown version, bad mesh, bad annulus ring, count mismatches,
// short tracings, dangling cord references) and returns nullopt if there was any.
std::optional<ValveCase> loadCase(const std::filesystem::path& directory, Diagnostics& diagnostics);

// Why `name` cannot name a case, or "" when it can. The name titles figures (SVG, where a NUL
// or other control character is not allowed even escaped) and table rows (where a newline ends
// the row, and a blank name leaves the Case cell empty). loadCase checks case.json's "name"
// with it, make-valve and import-mesh their --name before writing anything.
std::string caseNameProblem(const std::string& name);

// The checks loadCase makes of a case's open mesh as read from `file`: its span (a valve's size
// in millimetres; first, because the zero-area tolerance is relative to it and one vertex at
// 1e10 mm would make every triangle "degenerate"), then checkMesh (indices, finite coordinates,
// areas, manifold edges, no stray vertex). import-mesh runs them on its mesh before deriving
// anything from it. Returns false with the problems in `diagnostics`.
bool checkValveMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const std::string& file,
                    Diagnostics& diagnostics);

// Reads a tracings file on its own (the format of case.json's "tracings", docs/case-format.md),
// e.g. to add tracings to a case being built: curve files it names are relative to its own
// directory, leaflet names resolve against `leaflet_names`. Returns false with the problems in
// `diagnostics`.
bool readTracingsFile(const std::filesystem::path& path,
                      const std::vector<std::string>& leaflet_names, std::vector<Tracing>& tracings,
                      Diagnostics& diagnostics);

// Writes a case directory: open.ply, leaflets.json, annulus_ring.json, annulus_closed.json,
// and tracings.json / pm_tips.json / cords.json / tissue.json when present, then case.json
// last (so an interrupted write leaves no loadable half-case). Each file is written atomically.
void writeCase(const std::filesystem::path& directory, const ValveCase& valve_case);
// Every file name writeCase may write, for the commands that declare their outputs
// (tools/staged_output.h).
std::vector<std::string> caseFileNames();

// Regional tissue file (docs/case-format.md, `tissue.json`): reads `path` (named `name` in
// messages) into valve_case.tissue_stiffness, checking one factor in (0, 1000] per mesh
// vertex; false with the problems reported otherwise. writeTissueFile writes it atomically.
bool loadTissueFile(const std::filesystem::path& path, const std::string& name,
                    ValveCase& valve_case, Diagnostics& diagnostics);
void writeTissueFile(const std::filesystem::path& path, const Eigen::VectorXd& factors);

}  // namespace chordfit
