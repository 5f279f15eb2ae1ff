#include "core/atomic_file.h"

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
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

namespace {

namespace fs = std::filesystem;

// The temporary file of `path` written by process `pid`: hidden, and named so that no file a
// user keeps beside it is taken for one (a backup "cords.json.tmp.20261129" was, and removed).
std::string temporaryPrefix(const fs::path& path) {
  return "." + path.filename().string() + kTemporaryInfix;
}

// The pid in a temporary file's name beside `path` (temporaryPrefix), or -1 for any other.
long temporaryPid(const fs::path& path, const std::string& entry) {
  const std::string prefix = temporaryPrefix(path);
  if (entry.size() <= prefix.size() || entry.size() > prefix.size() + 9 ||
      entry.compare(0, prefix.size(), prefix) != 0)
    return -1;
  const std::string digits = entry.substr(prefix.size());
  if (digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::stol(digits);
}

// Writes all of `bytes` to `fd`; false (errno set) when the device refuses.
bool writeAll(int fd, const std::string& bytes) {
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    written += static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

bool leftByEndedProcess(const std::filesystem::path& entry, long pid) {
  std::error_code ec;
  const auto age = fs::file_time_type::clock::now() - fs::last_write_time(entry, ec);
  if (ec || age < std::chrono::seconds(2)) return false;
  // Read-only, as a directory can only be opened: on an NFS mount that maps flock to POSIX
  // locks the lock then fails, and the entry is kept (never a live one removed).
  const int fd = ::open(entry.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return false;
  const bool free = ::flock(fd, LOCK_EX | LOCK_NB) == 0;
  ::close(fd);
  return free && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

void removeAbandonedTemporaries(const std::filesystem::path& path) {
  std::error_code ec;
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const long pid = temporaryPid(path, it->path().filename().string());
    std::error_code ignored;
    if (pid <= 0 || pid == ::getpid() || !fs::is_regular_file(it->symlink_status(ignored)))
      continue;
    if (leftByEndedProcess(it->path(), pid)) fs::remove(it->path(), ignored);
  }
}

void writeFileAtomically(const std::filesystem::path& requested, const std::string& bytes) {
  std::error_code ec;
  const fs::path path = writeTarget(requested);
  if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
  removeAbandonedTemporaries(path);
  // The pid keeps concurrent writers (e.g. sharded experiments) from sharing a temp file; the
  // lock, held while it is written, keeps removeAbandonedTemporaries of other runs off it.
  const fs::path tmp = path.parent_path() / (temporaryPrefix(path) + std::to_string(::getpid()));
  errno = 0;
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0)
    throw std::runtime_error(requested.string() + ": cannot open for writing" + systemReason());
  // Advisory and not waited for: a file system without locks, or an NFS server in its grace
  // period, still gets its file.
  ::flock(fd, LOCK_EX | LOCK_NB);
  errno = 0;
  bool written = writeAll(fd, bytes);
  std::string reason = systemReason();
  // close() can report what write() did not (a full quota on NFS): checked before the rename,
  // so that a failed file is never put in place.
  errno = 0;
  if (::close(fd) != 0 && written) written = false, reason = systemReason();
  if (!written) {
    fs::remove(tmp, ec);
    throw std::runtime_error(requested.string() + ": write failed" + reason);
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
