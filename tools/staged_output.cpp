#include "tools/staged_output.h"

#include <unistd.h>

#include <stdexcept>
#include <system_error>
#include <vector>

namespace chordfit::cli {

namespace fs = std::filesystem;

StagedOutput::StagedOutput(const fs::path& out_dir)
    : out_(out_dir), staging_(out_dir / (".staging-" + std::to_string(::getpid()))) {
  fs::create_directories(out_);
  fs::remove_all(staging_);
  fs::create_directories(staging_);
}

StagedOutput::~StagedOutput() {
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
}

void StagedOutput::publish() {
  std::vector<fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(staging_))
    files.push_back(entry.path().filename());
  // A rename onto a directory fails; found before the first move, it leaves the output
  // directory as it was instead of half old, half new.
  for (const fs::path& name : files) {
    std::error_code ec;
    // symlink_status: a link to a directory is replaced by the rename, not in the way.
    if (fs::is_directory(fs::symlink_status(out_ / name, ec)) &&
        !fs::is_directory(staging_ / name, ec))
      throw std::runtime_error((out_ / name).string() +
                               ": a directory of that name is in the way of the output file "
                               "(nothing was written)");
  }
  for (const fs::path& name : files) fs::rename(staging_ / name, out_ / name);
}

}  // namespace chordfit::cli
