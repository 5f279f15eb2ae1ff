#include "core/atomic_file.h"

#include <cerrno>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <unistd.h>

namespace chordfit {

namespace {

// The file a write to `path` should replace: through a symbolic link, its target, so that a
// link the user made (e.g. latest.json -> runs/7/cords.json) still points at the new result
// instead of being replaced by a plain file. A dangling link is left to the caller's checks.
std::filesystem::path writeTarget(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_symlink(fs::symlink_status(path, ec)) || !fs::exists(path, ec)) return path;
  const fs::path target = fs::canonical(path, ec);
  return ec ? path : target;
}

// " (No space left on device)" for the errno a failed open or write left, or "" without one.
std::string systemReason() {
  const int error = errno;
  return error == 0 ? "" : " (" + std::error_code(error, std::generic_category()).message() + ")";
}

}  // namespace

void writeFileAtomically(const std::filesystem::path& requested, const std::string& bytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path path = writeTarget(requested);
  if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
  // The pid keeps concurrent writers (e.g. sharded experiments) from sharing a temp file.
  fs::path tmp = path;
  tmp += ".tmp." + std::to_string(::getpid());
  {
    errno = 0;
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      throw std::runtime_error(requested.string() + ": cannot open for writing" + systemReason());
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) {
      const std::string reason = systemReason();
      fs::remove(tmp, ec);
      throw std::runtime_error(requested.string() + ": write failed" + reason);
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error(requested.string() + ": cannot move temporary file into place");
  }
}

std::string inputFileProblem(const std::filesystem::path& path, const std::string& what) {
  namespace fs = std::filesystem;
  if (path.empty()) return "no file given";
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found) return "file not found";
  // No permission, a loop of links: status() fails with a type of none, not a device.
  if (ec) return "cannot be read (" + ec.message() + ")";
  if (fs::is_directory(status)) return "is a directory, not " + what;
  if (!fs::is_regular_file(status)) return "is not a regular file (a device, a pipe or a socket)";
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) return "cannot be read (" + ec.message() + ")";
  if (size > kMaxInputFileBytes)
    return "is larger than " + std::to_string(kMaxInputFileBytes >> 20) +
           " MiB, the most an input file may have (" + std::to_string(size) + " bytes)";
  return "";
}

bool startsWithByteOrderMark(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char head[3] = {};
  return in.read(head, 3) && std::string(head, 3) == kUtf8ByteOrderMark;
}

bool readWholeFile(const std::filesystem::path& path, std::string& bytes) {
  bytes.clear();
  if (!inputFileProblem(path).empty()) return false;
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  bytes = ss.str();
  return true;
}

std::string cannotBeRead(const std::filesystem::path& path) {
  errno = 0;
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return "cannot be read" + systemReason();
  std::fclose(file);
  return "cannot be read";
}

}  // namespace chordfit
