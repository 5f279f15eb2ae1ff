#include "tools/staged_output.h"

#include <unistd.h>

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "core/atomic_file.h"

namespace chordfit::cli {

namespace fs = std::filesystem;

StagedOutput::StagedOutput(const fs::path& out_dir, std::vector<std::string> declared,
                           std::vector<std::string> superseded)
    : out_(out_dir),
      staging_(out_dir / (".staging-" + std::to_string(::getpid()))),
      declared_(std::move(declared)),
      superseded_(std::move(superseded)) {
  fs::create_directories(out_);
  fs::remove_all(staging_);
  fs::create_directories(staging_);
}

StagedOutput::~StagedOutput() {
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
}

namespace {

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// The names the record in `dir` lists (none when there is no record).
std::vector<std::string> recordedOutputs(const fs::path& dir) {
  std::vector<std::string> names;
  std::string text;
  if (!readWholeFile(dir / kOutputRecordName, text)) return names;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    if (!line.empty()) names.push_back(line);
  return names;
}

}  // namespace

StagedOutput::Published StagedOutput::publish() {
  std::vector<std::string> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(staging_)) {
    const std::string name = entry.path().filename().string();
    if (name == kOutputRecordName) continue;  // a nested run's (fit's closure); ours follows
    if (!contains(declared_, name))
      throw std::logic_error("internal: " + name +
                             " was written but is not among the command's declared output "
                             "files (nothing was published)");
    files.push_back(name);
  }
  std::sort(files.begin(), files.end());  // the same order of renames on every file system
  // A rename onto a directory fails; found before the first move, it leaves the output
  // directory as it was instead of half old, half new.
  for (const std::string& name : files) {
    std::error_code ec;
    // symlink_status: a link to a directory is replaced by the rename, not in the way.
    if (fs::is_directory(fs::symlink_status(out_ / name, ec)) &&
        !fs::is_directory(staging_ / name, ec))
      throw std::runtime_error((out_ / name).string() +
                               ": a directory of that name is in the way of the output file "
                               "(nothing was written)");
  }
  for (const std::string& name : files) fs::rename(staging_ / name, out_ / name);

  Published published;
  std::vector<std::string> stale;
  for (const std::string& name : declared_)
    (contains(files, name) ? published.written : stale).push_back(name);
  stale.insert(stale.end(), superseded_.begin(), superseded_.end());
  std::vector<std::string> record = recordedOutputs(out_);
  for (const std::string& name : stale) {
    std::error_code ec;
    if (!contains(record, name) || fs::is_directory(fs::symlink_status(out_ / name, ec))) continue;
    if (fs::remove(out_ / name, ec)) published.removed.push_back(name);
  }
  // The record: what it listed and is still there, and what this run wrote.
  std::vector<std::string> kept;
  for (const std::string& name : record) {
    std::error_code ec;
    if (!contains(files, name) && fs::exists(fs::symlink_status(out_ / name, ec)))
      kept.push_back(name);
  }
  kept.insert(kept.end(), files.begin(), files.end());
  std::sort(kept.begin(), kept.end());
  std::string text;
  for (const std::string& name : kept) text += name + "\n";
  writeFileAtomically(out_ / kOutputRecordName, text);
  return published;
}

std::string wroteLine(const fs::path& out_dir, const StagedOutput::Published& files) {
  std::string line = "wrote ";
  for (std::size_t i = 0; i < files.written.size(); ++i)
    line += i == 0 ? (out_dir / files.written[i]).string() : ", " + files.written[i];
  for (std::size_t i = 0; i < files.removed.size(); ++i)
    line += (i == 0 ? "; removed " : ", ") + files.removed[i];
  if (!files.removed.empty()) line += " (an earlier run's)";
  return line;
}

}  // namespace chordfit::cli
