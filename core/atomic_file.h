// Atomic output: write to a temporary file beside the target, then rename over it, so a
// crash or an error never leaves a half-written result. And the input side: which paths a
// reader may read at all, and reading them whole.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace chordfit {

// Writes `bytes` to `path` atomically: to ".<name>.chordfit-tmp.<pid>" in the same directory,
// then renamed over it.
// Creates missing parent directories. A symbolic link is written through: its target gets the
// bytes and the link stays. Throws std::runtime_error naming the path on failure.
void writeFileAtomically(const std::filesystem::path& path, const std::string& bytes);

// What a temporary file's name adds to its target's: "." before it, this and the pid after.
inline constexpr char kTemporaryInfix[] = ".chordfit-tmp.";

// Whether `entry`, a temporary file or directory named with the pid of the process writing
// it, was left by a process that has ended: its lock is free (a live writer holds a flock on
// it, which another container on this host sees too, where its pid means nothing), no process
// of that pid lives on this machine, and it is older than 2 s (so that a writer between its
// open and its lock keeps it). A pid reused by an unrelated process keeps it for a later run.
// On an NFS mount flock may not reach other clients, or may fail on a read-only descriptor:
// where the lock cannot be taken the entry is kept; where it is local to each client, a live
// writer on another client is known only by its age.
bool leftByEndedProcess(const std::filesystem::path& entry, long pid);

// Removes the temporary files ".<name>.chordfit-tmp.<pid>" beside `path` that writers no
// longer alive left (a write killed between its open and its rename: SIGKILL, Ctrl-C);
// writeFileAtomically calls it first. A live writer's file is kept (leftByEndedProcess).
void removeAbandonedTemporaries(const std::filesystem::path& path);

// The largest input file any reader takes. A fine valve mesh (a million triangles, ten times
// the finest the project makes) is ~60 MB of ASCII PLY and the JSON side files are smaller;
// parsing holds several times the text in memory, so a file beyond this is a wrong file (a
// disk image, a log), not a valve, and reading it could exhaust the machine.
constexpr std::uintmax_t kMaxInputFileBytes = std::uintmax_t{512} << 20;

// Why `path` cannot be read as an input file, or "" when it can: "no file given" (an empty
// path), "file not found", "is a directory, not <what>", "is not a regular file" (a device or
// a pipe: /dev/zero would be read forever) or a size above kMaxInputFileBytes.
std::string inputFileProblem(const std::filesystem::path& path, const std::string& what = "a file");

// The UTF-8 byte-order mark some editors and spreadsheet exports put at a text file's start.
inline constexpr const char* kUtf8ByteOrderMark = "\xEF\xBB\xBF";
// Whether the file at `path` starts with it (false when it cannot be read).
bool startsWithByteOrderMark(const std::filesystem::path& path);

// Reads a whole file. Returns false (and leaves `bytes` empty) when it cannot be opened or
// inputFileProblem refuses it; callers that report why check inputFileProblem first.
bool readWholeFile(const std::filesystem::path& path, std::string& bytes);

// "cannot be read (Permission denied)": why a file that inputFileProblem passed did not open
// (the operating system's reason, found by opening it once more).
std::string cannotBeRead(const std::filesystem::path& path);

}  // namespace chordfit
