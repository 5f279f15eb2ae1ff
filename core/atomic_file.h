// Atomic output: write to a temporary file beside the target, then rename over it, so a
// crash or an error never leaves a half-written result.
#pragma once

#include <filesystem>
#include <string>

namespace chordfit {

// Writes `bytes` to `path` atomically (temp file in the same directory + rename).
// Creates missing parent directories. Throws std::runtime_error naming the path on failure.
void writeFileAtomically(const std::filesystem::path& path, const std::string& bytes);

// Reads a whole file. Returns false (and leaves `bytes` empty) when it cannot be opened.
bool readWholeFile(const std::filesystem::path& path, std::string& bytes);

}  // namespace chordfit
