// A command's output files are written into a staging directory inside the output directory
// and moved into it only when the command has written all of them: a failure part-way (a
// full disk, an exception) leaves the output directory as it was, never half of a result.
// Each file is already written atomically (atomic_file.h); this makes the set atomic up to the
// final renames, which need no space and do not fail for lack of it.
//
// The staging directory knows the names the command declares (its *OutputFiles function in
// commands.h, which main.cpp's pre-flight checks before any work): a file written but not
// declared is refused at publish(), so the pre-flight's list cannot drift from the writer.
// Publishing also removes the command's files that this run did not write (declared but not
// written, or `superseded`), so the directory never holds one run's results beside an earlier
// run's, e.g. opened.ply of an earlier `simulate --phase open` beside a new closed.ply.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace chordfit::cli {

class StagedOutput {
 public:
  // Creates out_dir if missing and a fresh staging directory inside it. `declared`: every
  // file name the command may write there. `superseded`: names of files an earlier run of the
  // command, with other options, may have left there and this run does not write.
  StagedOutput(const std::filesystem::path& out_dir, std::vector<std::string> declared,
               std::vector<std::string> superseded = {});
  // Removes the staging directory and whatever is still in it.
  ~StagedOutput();
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  // Where the command writes its files.
  const std::filesystem::path& dir() const { return staging_; }
  // Moves every file written into the staging directory to the output directory, replacing
  // files of the same name, then removes the declared files not written and the superseded
  // ones (files only, never a directory); returns the names written, in the declared order.
  // Throws, changing nothing, when a written file was not declared or a directory is in the
  // way of one.
  std::vector<std::string> publish();

 private:
  std::filesystem::path out_, staging_;
  std::vector<std::string> declared_, superseded_;
};

// "wrote DIR/first, second, ...": the line a command prints after publishing `names`.
std::string wroteLine(const std::filesystem::path& out_dir, const std::vector<std::string>& names);

}  // namespace chordfit::cli
