// A command's output files are written into a staging directory inside the output directory
// and moved into it only when the command has written all of them: a failure part-way (a
// full disk, an exception) leaves the output directory as it was, never half of a result.
// Each file is already written atomically (atomic_file.h); this makes the set atomic up to the
// final renames, which need no space and do not fail for lack of it.
//
// The staging directory knows the names the command declares (its *OutputFiles function in
// commands.h, which main.cpp's pre-flight checks before any work): a file written but not
// declared is refused at publish(), so the pre-flight's list cannot drift from the writer.
// Publishing also removes the command's files that an earlier run wrote and this run does not
// (declared but not written, or `superseded`), e.g. opened.ply of an earlier `simulate --phase
// open` beside a new closed.ply: only names a chordfit run published there, as the directory's
// record of them (.chordfit-outputs) says, so a file the user put there is never removed.
//
// A declared name may be a relative path ("truth/case/case.json": make-case's truth): each
// directory's files are recorded in that directory's own record, so a record names only the
// files beside it, and a directory that held nothing but an earlier run's files is removed
// with them.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace chordfit::cli {

// `text` (an error message) with the staging directories taken out of the paths it names,
// so that a failed write names the file as the user asked for it ("out/closed.ply", not
// "out/.staging-24775/.staging-24775/closed.ply").
std::string withoutStagingDirectories(const std::string& text);

class StagedOutput {
 public:
  // Creates out_dir if missing and a fresh staging directory inside it. `declared`: every
  // file name (or relative path) the command may write there. `superseded`: names of files an
  // earlier run of the command with other options, or of another command writing the same kind
  // of directory (a case), may have left there and this run does not write.
  // `command`: the command's name, recorded with each file it publishes, so that a run of
  // another command that replaces one says so.
  StagedOutput(const std::filesystem::path& out_dir, std::vector<std::string> declared,
               std::vector<std::string> superseded = {}, std::string command = "");
  // Removes the staging directory and whatever is still in it, and out_dir too when this
  // created it and nothing was published (so a refused or failed run leaves no empty
  // directory behind).
  ~StagedOutput();
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  // Where the command writes its files.
  const std::filesystem::path& dir() const { return staging_; }
  struct Published {
    std::vector<std::string> written;  // in the declared order
    std::vector<std::string> removed;  // an earlier run's files this run superseded
    // Files another command published that this run replaced: "sections.svg (fit's)".
    std::vector<std::string> replaced;
  };
  // Moves every file written into the staging directory to the output directory, replacing
  // files of the same name, then removes the earlier run's files this run supersedes (files
  // only; a directory only when that leaves it empty) and updates the records. Throws,
  // changing nothing, when a written file was not declared, a directory is in the way of one
  // or a file in the way of a directory it goes into.
  Published publish();

 private:
  std::filesystem::path out_, staging_;
  std::vector<std::string> declared_, superseded_;
  std::string command_;
  bool created_out_ = false, published_ = false;
  int lock_fd_ = -1;  // holds the staging directory's lock (staged_output.cpp) while open
};

// The command name make-valve, make-case and import-mesh record: each writes a whole case
// and replaces the others' case files by design, which is not worth a note.
inline constexpr const char* kCaseWriter = "case";

// The record of the files chordfit runs published in a directory: one per line, its name and,
// after a tab, the command that published it.
inline constexpr const char* kOutputRecordName = ".chordfit-outputs";

// What stands in `out` where the output file `name` (a relative path) would go, or nullopt:
// a directory where the file goes (a rename onto it fails), or something not a directory
// (a file, a link to a file or to nothing) where one of its directories goes. Shared by the
// commands' check before any work and by publish().
struct InTheWay {
  std::filesystem::path path;
  std::string what;
};
// What is wrong with writing `file` by temp + rename when it exists and is neither a regular
// file nor a directory (a device, FIFO or socket, following links), or "".
std::string specialFileProblem(const std::filesystem::path& file);
std::optional<InTheWay> whatIsInTheWay(const std::filesystem::path& out, const std::string& name);

// Whether a chordfit run published `file`: its directory's record lists it.
bool publishedByChordfit(const std::filesystem::path& file);

// Drops `file`'s name from its directory's record: a command that writes one file of the
// user's choosing (heuristic, edit-cords, metrics --out) has replaced what a staged run
// published there, and a later staged run must not take the user's file for its own stale
// output (make-valve removed a cords.json the user had written with heuristic).
void forgetPublished(const std::filesystem::path& file);

// "wrote DIR/first, second, ...[; removed x, y (an earlier run's)]": the line a command prints
// after publishing.
std::string wroteLine(const std::filesystem::path& out_dir, const StagedOutput::Published& files);
// Its tail, "; removed x, y (an earlier run's)", or "" when nothing was removed: for a command
// that names what it wrote in its own words (make-case).
std::string removedNote(const StagedOutput::Published& files);

}  // namespace chordfit::cli
