// A command's output files are written into a staging directory inside the output directory
// and moved into it only when the command has written all of them: a failure part-way (a
// full disk, an exception) leaves the output directory as it was, never half of a result.
// Each file is already written atomically (atomic_file.h); this makes the set atomic up to the
// final renames, which need no space and do not fail for lack of it.
#pragma once

#include <filesystem>
#include <string>

namespace chordfit::cli {

class StagedOutput {
 public:
  // Creates out_dir if missing and a fresh staging directory inside it.
  explicit StagedOutput(const std::filesystem::path& out_dir);
  // Removes the staging directory and whatever is still in it.
  ~StagedOutput();
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  // Where the command writes its files.
  const std::filesystem::path& dir() const { return staging_; }
  // Moves every file written into the staging directory to the output directory, replacing
  // files of the same name.
  void publish();

 private:
  std::filesystem::path out_, staging_;
};

}  // namespace chordfit::cli
