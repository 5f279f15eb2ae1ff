# Writes REVISION_FILE, a C++ header defining CHORDFIT_REVISION as the source tree's
# `git describe --always --dirty` ("unknown" outside git), and rewrites it only when the text
# changed, so a build recompiles the one file that includes it only after a commit or an edit.
# Run at every build (tools/CMakeLists.txt): `chordfit --version` then names the revision the
# binary was built from, which the benchmark records with every job.
# Only the source tree's own repository: a tree unpacked inside another one would otherwise
# take that repository's revision.
execute_process(
  COMMAND git -C "${SOURCE_DIR}" rev-parse --show-toplevel
  OUTPUT_VARIABLE toplevel
  OUTPUT_STRIP_TRAILING_WHITESPACE
  ERROR_QUIET
  RESULT_VARIABLE not_a_repository)
set(revision "")
get_filename_component(source_real "${SOURCE_DIR}" REALPATH)
if(NOT not_a_repository)
  get_filename_component(toplevel_real "${toplevel}" REALPATH)
  if(toplevel_real STREQUAL source_real)
    execute_process(
      COMMAND git -C "${SOURCE_DIR}" describe --always --dirty
      OUTPUT_VARIABLE revision
      OUTPUT_STRIP_TRAILING_WHITESPACE
      ERROR_QUIET
      RESULT_VARIABLE failed)
    if(failed)
      set(revision "")
    endif()
  endif()
endif()
if(revision STREQUAL "")
  set(revision "unknown")
endif()
set(content "// Generated at build time by cmake/write_revision.cmake; do not edit.\n#pragma once\n#define CHORDFIT_REVISION \"${revision}\"\n")
set(old "")
if(EXISTS "${REVISION_FILE}")
  file(READ "${REVISION_FILE}" old)
endif()
if(NOT old STREQUAL content)
  file(WRITE "${REVISION_FILE}" "${content}")
endif()
