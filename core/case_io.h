// Case directories (format v1, docs/case-format.md): case.json plus the files it names.
#pragma once

#include <filesystem>
#include <optional>

#include "core/case_data.h"
#include "core/diagnostics.h"

namespace chordfit {

constexpr int kCaseFormatVersion = 1;

// Reads and validates a case directory. Reports every problem it can find (missing files,
// malformed JSON, wrong types, unknown version, bad mesh, bad annulus ring, count mismatches,
// short tracings, dangling cord references) and returns nullopt if there was any.
std::optional<ValveCase> loadCase(const std::filesystem::path& directory, Diagnostics& diagnostics);

// Writes a case directory: open.ply, leaflets.json, annulus_ring.json, annulus_closed.json,
// and tracings.json / pm_tips.json / cords.json when present, then case.json last (so an
// interrupted write leaves no loadable half-case). Each file is written atomically.
void writeCase(const std::filesystem::path& directory, const ValveCase& valve_case);

}  // namespace chordfit
