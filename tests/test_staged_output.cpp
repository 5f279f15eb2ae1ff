// The staging directory behind every command's output set (tools/staged_output.h): all or
// nothing, and only the file names the command declares (which its pre-flight checks).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "tests/test_support.h"
#include "tools/staged_output.h"

namespace chordfit::cli {
namespace {

namespace fs = std::filesystem;
using chordfit::testing::TempDir;

void writeText(const fs::path& file, const std::string& text) { std::ofstream(file) << text; }

std::string readText(const fs::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A failed write names the file as the user will find it (a full disk read "full/f/
// .staging-24775/.staging-24775/closed.ply: write failed"); other dot-directories stay.
TEST(StagedOutput, ErrorsNameFilesWithoutTheStagingDirectories) {
  EXPECT_EQ(withoutStagingDirectories(
                "full/f/.staging-24775/.staging-24775/closed.ply: write failed (No space left)"),
            "full/f/closed.ply: write failed (No space left)");
  EXPECT_EQ(withoutStagingDirectories("/a/.staging-1/b.json and /c/.staging-x/d"),
            "/a/b.json and /c/.staging-x/d");
}

// A run killed part-way (SIGKILL, Ctrl-C) leaves its staging directory behind; the next run
// into the same directory removes it, but not one whose process still runs (a concurrent run).
TEST(StagedOutput, RemovesTheStagingDirectoriesOfRunsThatNoLongerExist) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  const pid_t child = ::fork();  // a pid known to have ended
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ::waitpid(child, nullptr, 0);
  const fs::path abandoned = out / (".staging-" + std::to_string(child));
  const fs::path running = out / (".staging-" + std::to_string(::getppid()));
  const fs::path not_staging = out / ".staging-notes";
  // A run on another host or in another container sharing the directory: its pid means
  // nothing here (this one has ended), its lock is what tells.
  const pid_t other_host_child = ::fork();
  if (other_host_child == 0) ::_exit(0);
  ASSERT_GT(other_host_child, 0);
  ::waitpid(other_host_child, nullptr, 0);
  const fs::path locked = out / (".staging-" + std::to_string(other_host_child));
  for (const fs::path& dir : {abandoned, running, not_staging, locked}) {
    fs::create_directories(dir);
    writeText(dir / "cords.json", "{");
    fs::last_write_time(dir, fs::file_time_type::clock::now() - std::chrono::minutes(5));
  }
  const int lock = ::open(locked.c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(lock, 0);
  ASSERT_EQ(::flock(lock, LOCK_EX | LOCK_NB), 0);
  {
    StagedOutput staged(out, {"a.txt"});
    writeText(staged.dir() / "a.txt", "a");
    staged.publish();
  }
  EXPECT_FALSE(fs::exists(abandoned)) << "its run has ended";
  EXPECT_TRUE(fs::exists(running / "cords.json")) << "its process still runs";
  EXPECT_TRUE(fs::exists(not_staging / "cords.json")) << "not a staging directory's name";
  EXPECT_TRUE(fs::exists(locked / "cords.json")) << "its run holds the lock";
  ::close(lock);
  EXPECT_EQ(readText(out / "a.txt"), "a");
}

TEST(StagedOutput, PublishesTheWrittenFilesInDeclaredOrderAndRecordsThem) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  StagedOutput::Published published;
  {
    StagedOutput staged(out, {"a.txt", "b.txt", "c.txt"});
    writeText(staged.dir() / "c.txt", "c");
    writeText(staged.dir() / "a.txt", "a");
    EXPECT_FALSE(fs::exists(out / "a.txt"));  // nothing is visible before publishing
    published = staged.publish();
  }
  EXPECT_EQ(published.written, (std::vector<std::string>{"a.txt", "c.txt"}));
  EXPECT_TRUE(published.removed.empty());
  EXPECT_EQ(readText(out / "a.txt"), "a");
  EXPECT_EQ(readText(out / "c.txt"), "c");
  EXPECT_EQ(readText(out / kOutputRecordName), "a.txt\nc.txt\n");
  // The two files and the record; no staging directory is left.
  EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator()), 3);
  EXPECT_EQ(wroteLine(out, published), "wrote " + (out / "a.txt").string() + ", c.txt");
}

// The record names the command that published each file, and a run of another command that
// replaces one says so (a compare into a fit's directory replaced the fit's sections.svg);
// a record without commands (written before they were recorded) gives no note.
TEST(StagedOutput, SaysWhichFilesOfAnotherCommandItReplaces) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  auto run = [&](const std::string& command, const std::vector<std::string>& names) {
    StagedOutput staged(out, names, {}, command);
    for (const std::string& name : names) writeText(staged.dir() / name, command);
    return staged.publish();
  };
  run("fit", {"report.md", "sections.svg"});
  EXPECT_EQ(readText(out / kOutputRecordName), "report.md\tfit\nsections.svg\tfit\n");
  EXPECT_TRUE(run("fit", {"report.md", "sections.svg"}).replaced.empty()) << "its own files";
  const StagedOutput::Published compared = run("compare", {"compare.md", "sections.svg"});
  EXPECT_EQ(compared.replaced, (std::vector<std::string>{"sections.svg (fit's)"}));
  EXPECT_EQ(wroteLine(out, compared), "wrote " + (out / "compare.md").string() +
                                          ", sections.svg; replaced another command's "
                                          "sections.svg (fit's)");
  EXPECT_EQ(readText(out / kOutputRecordName),
            "compare.md\tcompare\nreport.md\tfit\nsections.svg\tcompare\n");
  writeText(out / kOutputRecordName, "report.md\n");  // an older record
  EXPECT_TRUE(run("compare", {"report.md"}).replaced.empty());
}

TEST(StagedOutput, RemovesOnlyAnEarlierRunsRecordedFilesThisRunDoesNotWrite) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  fs::create_directories(out / "d.txt");
  for (const char* name : {"a.txt", "b.txt", "old.txt", "users.txt", "other.txt"})
    writeText(out / name, "earlier");
  // An earlier run published all but users.txt, which the user put there.
  writeText(out / kOutputRecordName, "a.txt\nb.txt\nd.txt\nold.txt\nother.txt\n");
  StagedOutput::Published published;
  {
    StagedOutput staged(out, {"a.txt", "b.txt", "d.txt", "users.txt"}, {"old.txt"});
    writeText(staged.dir() / "a.txt", "a");
    published = staged.publish();
  }
  EXPECT_EQ(published.written, std::vector<std::string>{"a.txt"});
  EXPECT_EQ(published.removed, (std::vector<std::string>{"b.txt", "old.txt"}));
  EXPECT_EQ(readText(out / "a.txt"), "a");
  EXPECT_FALSE(fs::exists(out / "b.txt")) << "declared, not written: the earlier run's";
  EXPECT_FALSE(fs::exists(out / "old.txt")) << "superseded";
  EXPECT_TRUE(fs::is_directory(out / "d.txt")) << "a directory is never removed";
  EXPECT_EQ(readText(out / "users.txt"), "earlier") << "declared, but no run recorded it";
  EXPECT_EQ(readText(out / "other.txt"), "earlier") << "recorded, but not this command's";
  EXPECT_EQ(readText(out / kOutputRecordName), "a.txt\nd.txt\nother.txt\n");
  EXPECT_EQ(wroteLine(out, published),
            "wrote " + (out / "a.txt").string() + "; removed b.txt, old.txt (an earlier run's)");
}

TEST(StagedOutput, AnUndeclaredFileIsRefusedAndNothingIsPublished) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  {
    StagedOutput staged(out, {"a.txt"});
    writeText(staged.dir() / "a.txt", "a");
    writeText(staged.dir() / "stray.txt", "s");
    try {
      staged.publish();
      FAIL() << "publish() accepted an undeclared file";
    } catch (const std::logic_error& e) {
      EXPECT_NE(std::string(e.what()).find("stray.txt"), std::string::npos) << e.what();
    }
  }
  // The staging directory is gone, nothing was moved, and the directory this run created
  // is gone with them.
  EXPECT_FALSE(fs::exists(out));
}

// A run that publishes nothing (refused after staging, or failed) leaves an output directory
// that was there as it was, and removes one it created: make-valve and import-mesh each did
// this on their own before.
TEST(StagedOutput, ARunThatPublishesNothingLeavesNoDirectoryItCreated) {
  TempDir tmp;
  { StagedOutput staged(tmp.path() / "new", {"a.txt"}); }
  EXPECT_FALSE(fs::exists(tmp.path() / "new"));
  fs::create_directories(tmp.path() / "old");
  { StagedOutput staged(tmp.path() / "old", {"a.txt"}); }
  EXPECT_TRUE(fs::is_directory(tmp.path() / "old"));
  EXPECT_TRUE(fs::is_empty(tmp.path() / "old"));
}

TEST(StagedOutput, ADirectoryInTheWayRefusesTheWholeSet) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  fs::create_directories(out / "b.txt");
  {
    StagedOutput staged(out, {"a.txt", "b.txt"});
    writeText(staged.dir() / "a.txt", "a");
    writeText(staged.dir() / "b.txt", "b");
    EXPECT_THROW(staged.publish(), std::runtime_error);
  }
  EXPECT_FALSE(fs::exists(out / "a.txt"));
  EXPECT_TRUE(fs::is_directory(out / "b.txt"));
}

// make-case's truth: files in subdirectories, each directory with its own record, so that
// no record names a file outside its directory (the case's own never mentions the truth).
TEST(StagedOutput, PublishesFilesInSubdirectoriesWithTheRecordOfEachBesideThem) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  StagedOutput::Published published;
  {
    StagedOutput staged(out, {"case.json", "truth/truth.json", "truth/case/case.json"});
    fs::create_directories(staged.dir() / "truth" / "case");
    writeText(staged.dir() / "case.json", "case");
    writeText(staged.dir() / "truth" / "truth.json", "truth");
    writeText(staged.dir() / "truth" / "case" / "case.json", "fine case");
    published = staged.publish();
  }
  EXPECT_EQ(published.written,
            (std::vector<std::string>{"case.json", "truth/truth.json", "truth/case/case.json"}));
  EXPECT_EQ(readText(out / "truth" / "case" / "case.json"), "fine case");
  EXPECT_EQ(readText(out / kOutputRecordName), "case.json\n");
  EXPECT_EQ(readText(out / "truth" / kOutputRecordName), "truth.json\n");
  EXPECT_EQ(readText(out / "truth" / "case" / kOutputRecordName), "case.json\n");
  EXPECT_TRUE(publishedByChordfit(out / "truth" / "case" / "case.json"));
  EXPECT_FALSE(publishedByChordfit(out / "truth" / "case" / "open.ply"));
}

// A later run that writes no truth (make-valve over a make-case directory) supersedes it: the
// earlier run's files go, and a directory with them, unless the user put something there.
TEST(StagedOutput, RemovesAnEarlierRunsSubdirectoryUnlessTheUserPutAFileInIt) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  const std::vector<std::string> truth = {"truth/truth.json", "truth/case/case.json",
                                          "truth/case/tissue.json"};
  {
    const std::vector<std::string> earlier = {"case.json", truth[0], truth[1], truth[2]};
    StagedOutput staged(out, earlier);
    fs::create_directories(staged.dir() / "truth" / "case");
    for (const std::string& name : earlier) writeText(staged.dir() / name, "earlier");
    staged.publish();
  }
  writeText(out / "truth" / "notes.txt", "the user's");
  StagedOutput::Published published;
  {
    StagedOutput staged(out, {"case.json"}, truth);
    writeText(staged.dir() / "case.json", "later");
    published = staged.publish();
  }
  EXPECT_EQ(published.removed, truth);
  EXPECT_FALSE(fs::exists(out / "truth" / "case")) << "it held only the earlier run's files";
  EXPECT_EQ(readText(out / "truth" / "notes.txt"), "the user's");
  EXPECT_FALSE(fs::exists(out / "truth" / kOutputRecordName)) << "nothing of chordfit's left";
  EXPECT_EQ(readText(out / kOutputRecordName), "case.json\n");
  fs::remove(out / "truth" / "notes.txt");
  {
    StagedOutput staged(out, {"case.json"}, truth);
    writeText(staged.dir() / "case.json", "again");
    staged.publish();
  }
  EXPECT_TRUE(fs::is_directory(out / "truth")) << "a directory without a record is not ours";
}

TEST(StagedOutput, AFileWhereAnOutputDirectoryGoesRefusesTheWholeSet) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  fs::create_directories(out);
  writeText(out / "truth", "a file");
  {
    StagedOutput staged(out, {"case.json", "truth/truth.json"});
    fs::create_directories(staged.dir() / "truth");
    writeText(staged.dir() / "case.json", "case");
    writeText(staged.dir() / "truth" / "truth.json", "truth");
    EXPECT_THROW(staged.publish(), std::runtime_error);
  }
  EXPECT_FALSE(fs::exists(out / "case.json"));
  EXPECT_EQ(readText(out / "truth"), "a file");
}

}  // namespace
}  // namespace chordfit::cli
