#include "tools/staged_output.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "core/atomic_file.h"

namespace chordfit::cli {

namespace fs = std::filesystem;

std::string withoutStagingDirectories(const std::string& text) {
  static const std::regex staging(R"(/\.staging-[0-9]+(?=/))");
  return std::regex_replace(text, staging, "");
}

namespace {

// The pid in a staging directory's name ".staging-<pid>", or -1 for any other name.
long stagingPid(const std::string& name) {
  static const std::regex staging(R"(\.staging-([0-9]{1,9}))");
  std::smatch match;
  return std::regex_match(name, match, staging) ? std::stol(match[1].str()) : -1;
}

// An exclusive lock on `dir` held while the returned descriptor stays open (flock(2): it goes
// with the process, however it ends, and is seen across containers sharing the directory and
// by NFS clients); -1 when it is held elsewhere or cannot be taken.
int lockDirectory(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return -1;
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// Removes the staging directories in `out` of runs that no longer exist (leftByEndedProcess):
// a run killed before its destructor ran (SIGKILL, Ctrl-C) left its staged files there, and a
// later run would otherwise leave them for good.
void removeAbandonedStagingDirectories(const fs::path& out) {
  std::error_code ec;
  for (fs::directory_iterator it(out, ec), end; !ec && it != end; it.increment(ec)) {
    const long pid = stagingPid(it->path().filename().string());
    std::error_code ignored;
    if (pid <= 0 || pid == ::getpid() || !fs::is_directory(it->symlink_status(ignored))) continue;
    if (leftByEndedProcess(it->path(), pid)) fs::remove_all(it->path(), ignored);
  }
}

}  // namespace

StagedOutput::StagedOutput(const fs::path& out_dir, std::vector<std::string> declared,
                           std::vector<std::string> superseded, std::string command)
    : out_(out_dir),
      staging_(out_dir / (".staging-" + std::to_string(::getpid()))),
      declared_(std::move(declared)),
      superseded_(std::move(superseded)),
      command_(std::move(command)) {
  std::error_code ec;
  created_out_ = !fs::exists(out_, ec);
  fs::create_directories(out_);
  removeAbandonedStagingDirectories(out_);
  fs::remove_all(staging_);
  fs::create_directories(staging_);
  lock_fd_ = lockDirectory(staging_);  // so that no other run takes it for abandoned
}

StagedOutput::~StagedOutput() {
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
  if (lock_fd_ >= 0) ::close(lock_fd_);
  if (created_out_ && !published_) fs::remove(out_, ignored);  // only when empty
}

namespace {

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// What the record in `dir` lists: each file's name and the command that published it ("" in
// records written before they named it); empty when there is no record.
using Record = std::map<std::string, std::string>;
Record recordedOutputs(const fs::path& dir) {
  Record record;
  std::string text;
  if (!readWholeFile(dir / kOutputRecordName, text)) return record;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.empty()) continue;
    const std::size_t tab = line.find('\t');
    record[line.substr(0, tab)] = tab == std::string::npos ? "" : line.substr(tab + 1);
  }
  return record;
}

// Writes the record of `dir`: one file per line, "name<TAB>command" (the name alone when the
// command is not known).
void writeRecord(const fs::path& dir, const Record& record) {
  std::string text;
  for (const auto& [name, command] : record)
    text += name + (command.empty() ? "" : "\t" + command) + "\n";
  writeFileAtomically(dir / kOutputRecordName, text);
}

// The files written into `staging`, as paths relative to it ("a.txt", "truth/case/case.json"),
// sorted: the same order of renames on every file system. A nested run's record (fit's closure
// publishes into fit's staging directory) is not one of them; ours follow.
std::vector<std::string> stagedFiles(const fs::path& staging) {
  std::vector<std::string> files;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(staging)) {
    if (entry.is_directory() || entry.path().filename() == kOutputRecordName) continue;
    files.push_back(entry.path().lexically_relative(staging).generic_string());
  }
  std::sort(files.begin(), files.end());
  // A case's case.json last, the truth's before the case's own (as writeCase, core/case_io.h):
  // a new case directory holds no loadable case until every file is in place. Over an earlier
  // case a short window remains in which its case.json names new files.
  // Key: other files first (in name order), then the case.json files, deeper paths first.
  const auto key = [](const std::string& name) {
    const bool is_case = fs::path(name).filename() == "case.json";
    return std::pair<int, long>{is_case ? 1 : 0, is_case ? -static_cast<long>(name.size()) : 0};
  };
  std::stable_sort(files.begin(), files.end(),
                   [&](const std::string& a, const std::string& b) { return key(a) < key(b); });
  return files;
}

}  // namespace

std::string specialFileProblem(const fs::path& file) {
  std::error_code ec;
  const fs::file_status status = fs::status(file, ec);
  if (ec || !fs::exists(status) || fs::is_regular_file(status) || fs::is_directory(status))
    return "";
  // The rename of an atomic write would replace the node itself (as root, `--out /dev/null`
  // would leave a regular file where the system's /dev/null was).
  return "is not a regular file (a device, FIFO or socket); give a file to write";
}

std::optional<InTheWay> whatIsInTheWay(const fs::path& out, const std::string& name) {
  std::error_code ec;
  // symlink_status: a link to a directory is replaced by the rename, not in the way.
  if (fs::is_directory(fs::symlink_status(out / name, ec)))
    return InTheWay{out / name, "a directory of that name is in the way of an output file"};
  if (const std::string special = specialFileProblem(out / name); !special.empty())
    return InTheWay{out / name, special};
  for (fs::path dir = fs::path(name).parent_path(); !dir.empty(); dir = dir.parent_path()) {
    // Anything there that is not a directory, following links: a file, or a link to a file
    // or to nothing (a dangling link made the directory's creation fail after the first
    // renames).
    const fs::path place = out / dir;
    if (fs::exists(fs::symlink_status(place, ec)) && !fs::is_directory(fs::status(place, ec)))
      return InTheWay{place, "a file of that name is in the way of an output directory"};
  }
  return std::nullopt;
}

namespace {

// The directories (relative to the output directory, "" for itself) that hold any of `names`,
// with every directory above them; deepest first, so a directory is tidied after those in it.
std::vector<std::string> directoriesOf(const std::vector<std::string>& names) {
  std::vector<std::string> dirs = {""};
  for (const std::string& name : names) {
    for (fs::path dir = fs::path(name).parent_path(); !dir.empty(); dir = dir.parent_path())
      if (!contains(dirs, dir.generic_string())) dirs.push_back(dir.generic_string());
  }
  // A directory's path is a prefix of those in it, so it sorts before them.
  std::sort(dirs.rbegin(), dirs.rend());
  return dirs;
}

// Rewrites the record of `out`/`dir`: what it listed and is still there, and `written_here`
// (this run's files in it, by name). A subdirectory with neither gets no record; one whose
// record ends empty held only an earlier run's files: it loses the record, and is removed
// itself when nothing else is left in it (a file the user put there keeps it).
void updateRecord(const fs::path& out, const std::string& dir,
                  const std::vector<std::string>& written_here, const std::string& command) {
  const fs::path place = out / dir;
  const Record recorded = recordedOutputs(place);
  Record kept;
  for (const auto& [name, by] : recorded) {
    std::error_code ec;
    if (!contains(written_here, name) && fs::exists(fs::symlink_status(place / name, ec)))
      kept[name] = by;
  }
  for (const std::string& name : written_here) kept[name] = command;
  if (kept.empty() && !dir.empty()) {
    std::error_code ec;
    if (recorded.empty() && !fs::exists(place / kOutputRecordName, ec)) return;  // not ours
    fs::remove(place / kOutputRecordName, ec);
    // Only a real, empty directory: a link to one (the user's shared truth/) stays a link.
    if (fs::is_directory(fs::symlink_status(place, ec))) fs::remove(place, ec);
    return;
  }
  writeRecord(place, kept);
}

}  // namespace

bool publishedByChordfit(const fs::path& file) {
  return recordedOutputs(file.parent_path()).count(file.filename().string()) > 0;
}

void forgetPublished(const fs::path& file) {
  const fs::path dir = file.parent_path();
  Record record = recordedOutputs(dir);
  if (record.erase(file.filename().string()) == 0) return;
  writeRecord(dir, record);
}

StagedOutput::Published StagedOutput::publish() {
  const std::vector<std::string> files = stagedFiles(staging_);
  for (const std::string& name : files) {
    if (!contains(declared_, name))
      throw std::logic_error("internal: " + name +
                             " was written but is not among the command's declared output "
                             "files (nothing was published)");
  }
  // Found before the first move, a problem leaves the output directory as it was instead of
  // half old, half new.
  for (const std::string& name : files) {
    if (const auto problem = whatIsInTheWay(out_, name))
      throw std::runtime_error(problem->path.string() + ": " + problem->what +
                               " (nothing was written)");
  }
  Published published;
  // Another command's files this run replaces (a compare into a fit's directory replaced the
  // fit's sections.svg, which the fit's report.md shows): said in the wrote line.
  for (const std::string& name : files) {
    const Record record = recordedOutputs((out_ / name).parent_path());
    const auto by = record.find(fs::path(name).filename().string());
    if (by != record.end() && !by->second.empty() && !command_.empty() && by->second != command_)
      published.replaced.push_back(name + " (" + by->second + "'s)");
  }
  // Every directory first: a failure to create one then changes no file of the output.
  for (const std::string& name : files) fs::create_directories((out_ / name).parent_path());
  for (const std::string& name : files) fs::rename(staging_ / name, out_ / name);

  std::vector<std::string> stale;
  for (const std::string& name : declared_)
    (contains(files, name) ? published.written : stale).push_back(name);
  stale.insert(stale.end(), superseded_.begin(), superseded_.end());
  for (const std::string& name : stale) {
    std::error_code ec;
    if (!publishedByChordfit(out_ / name) || fs::is_directory(fs::symlink_status(out_ / name, ec)))
      continue;
    if (fs::remove(out_ / name, ec)) published.removed.push_back(name);
  }
  std::vector<std::string> names = declared_;
  names.insert(names.end(), superseded_.begin(), superseded_.end());
  for (const std::string& dir : directoriesOf(names)) {
    std::vector<std::string> written_here;
    for (const std::string& name : files)
      if (fs::path(name).parent_path().generic_string() == dir)
        written_here.push_back(fs::path(name).filename().string());
    updateRecord(out_, dir, written_here, command_);
  }
  published_ = true;
  return published;
}

std::string wroteLine(const fs::path& out_dir, const StagedOutput::Published& files) {
  std::string line = "wrote ";
  for (std::size_t i = 0; i < files.written.size(); ++i)
    line += i == 0 ? (out_dir / files.written[i]).string() : ", " + files.written[i];
  return line + removedNote(files);
}

std::string removedNote(const StagedOutput::Published& files) {
  std::string note;
  for (std::size_t i = 0; i < files.replaced.size(); ++i)
    note += (i == 0 ? "; replaced another command's " : ", ") + files.replaced[i];
  for (std::size_t i = 0; i < files.removed.size(); ++i)
    note += (i == 0 ? "; removed " : ", ") + files.removed[i];
  if (!files.removed.empty()) note += " (an earlier run's)";
  return note;
}

}  // namespace chordfit::cli
