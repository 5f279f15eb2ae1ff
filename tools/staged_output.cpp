#include "tools/staged_output.h"

#include <unistd.h>

#include <algorithm>
#include <stdexcept>
#include <system_error>

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

std::vector<std::string> StagedOutput::publish() {
  std::vector<std::string> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(staging_)) {
    const std::string name = entry.path().filename().string();
    if (std::find(declared_.begin(), declared_.end(), name) == declared_.end())
      throw std::logic_error("internal: " + name +
                             " was written but is not among the command's declared output "
                             "files (nothing was published)");
    files.push_back(name);
  }
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
  std::vector<std::string> published;
  std::vector<std::string> stale = superseded_;
  for (const std::string& name : declared_)
    (std::find(files.begin(), files.end(), name) != files.end() ? published : stale)
        .push_back(name);
  for (const std::string& name : stale) {
    std::error_code ec;
    if (!fs::is_directory(fs::symlink_status(out_ / name, ec))) fs::remove(out_ / name, ec);
  }
  return published;
}

std::string wroteLine(const fs::path& out_dir, const std::vector<std::string>& names) {
  std::string line = "wrote ";
  for (std::size_t i = 0; i < names.size(); ++i)
    line += i == 0 ? (out_dir / names[i]).string() : ", " + names[i];
  return line;
}

}  // namespace chordfit::cli
