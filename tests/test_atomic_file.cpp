// Atomic output (core/atomic_file.h): the whole file or nothing, and a symbolic link the user
// made is written through, not replaced.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>

#include <gtest/gtest.h>

#include "core/atomic_file.h"
#include "test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// The reason the operating system gives (the CLI test of a mode-000 file skips under root).
TEST(AtomicFile, CannotBeReadSaysWhy) {
  TempDir dir;
  EXPECT_EQ(cannotBeRead(dir / "absent.json"), "cannot be read (No such file or directory)");
  testing::writeText(dir / "present.json", "{}");
  EXPECT_EQ(cannotBeRead(dir / "present.json"), "cannot be read") << "no reason to give";
}

TEST(AtomicFile, WritesTheWholeFileAndLeavesNoTemporary) {
  TempDir dir;
  writeFileAtomically(dir / "a" / "out.json", "first");
  writeFileAtomically(dir / "a" / "out.json", "second");
  EXPECT_EQ(testing::readText(dir / "a" / "out.json"), "second");
  int entries = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir / "a")) ++entries;
  EXPECT_EQ(entries, 1) << "a temporary file was left beside the output";
}

// A write killed between its open and its rename (SIGKILL, Ctrl-C) leaves
// ".<name>.chordfit-tmp.<pid>"; the next write of that file removes it, but not a live
// writer's: one whose process runs here, one that holds its lock (a writer in another
// container), or one written a moment ago; nor a file of the user's named like one
// ("cords.json.tmp.<digits>", a dated backup, was taken for one and removed).
TEST(AtomicFile, RemovesTheTemporariesOfWritersThatNoLongerExist) {
  TempDir dir;
  auto endedPid = [] {
    const pid_t child = ::fork();
    if (child == 0) ::_exit(0);
    ::waitpid(child, nullptr, 0);
    return std::to_string(child);
  };
  const fs::path out = dir / "cords.json";
  const fs::path abandoned = dir / (".cords.json.chordfit-tmp." + endedPid());
  const fs::path running = dir / (".cords.json.chordfit-tmp." + std::to_string(::getppid()));
  const fs::path locked = dir / (".cords.json.chordfit-tmp." + endedPid());
  const fs::path fresh = dir / (".cords.json.chordfit-tmp." + endedPid());
  const fs::path other_file = dir / (".metrics.json.chordfit-tmp." + endedPid());
  const fs::path not_temporary = dir / ".cords.json.chordfit-tmp.notes";
  const fs::path users_backup = dir / "cords.json.tmp.20261129";
  const auto old = fs::file_time_type::clock::now() - std::chrono::minutes(5);
  for (const fs::path& file :
       {abandoned, running, locked, fresh, other_file, not_temporary, users_backup}) {
    testing::writeText(file, "{");
    if (file != fresh) fs::last_write_time(file, old);
  }
  const int lock = ::open(locked.c_str(), O_RDONLY);
  ASSERT_GE(lock, 0);
  ASSERT_EQ(::flock(lock, LOCK_EX | LOCK_NB), 0);
  writeFileAtomically(out, "{}");
  ::close(lock);
  EXPECT_EQ(testing::readText(out), "{}");
  EXPECT_FALSE(fs::exists(abandoned)) << "its writer has ended";
  EXPECT_TRUE(fs::exists(running)) << "its process still runs";
  EXPECT_TRUE(fs::exists(locked)) << "its writer holds the lock";
  EXPECT_TRUE(fs::exists(fresh)) << "written a moment ago";
  EXPECT_TRUE(fs::exists(other_file)) << "another file's, left for its own next write";
  EXPECT_TRUE(fs::exists(not_temporary)) << "not a temporary's name";
  EXPECT_TRUE(fs::exists(users_backup)) << "the user's file";
}

// latest.json -> runs/7/cords.json: the run's file gets the bytes and the link still points
// at it (a rename onto the link would have replaced it by a plain file).
TEST(AtomicFile, WritesThroughASymbolicLink) {
  TempDir dir;
  writeFileAtomically(dir / "runs" / "7" / "cords.json", "old");
  fs::create_symlink(fs::path("runs") / "7" / "cords.json", dir / "latest.json");
  writeFileAtomically(dir / "latest.json", "new");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / "latest.json")));
  EXPECT_EQ(testing::readText(dir / "runs" / "7" / "cords.json"), "new");
  EXPECT_EQ(testing::readText(dir / "latest.json"), "new");
}

}  // namespace
}  // namespace chordfit
