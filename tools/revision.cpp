#include "tools/revision.h"

#include "chordfit_revision.h"  // generated at build time: cmake/write_revision.cmake

namespace chordfit::cli {

const char* sourceRevision() { return CHORDFIT_REVISION; }

}  // namespace chordfit::cli
