// The source revision this chordfit was built from (`git describe --always --dirty` at build
// time, "unknown" outside git): printed by `chordfit --version`, recorded by the benchmark.
#pragma once

namespace chordfit::cli {

const char* sourceRevision();

}  // namespace chordfit::cli
