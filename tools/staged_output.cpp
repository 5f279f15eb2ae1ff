#include "tools/staged_output.h"

#include <unistd.h>

#include <system_error>

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
  for (const fs::directory_entry& entry : fs::directory_iterator(staging_))
    fs::rename(entry.path(), out_ / entry.path().filename());
}

}  // namespace chordfit::cli
