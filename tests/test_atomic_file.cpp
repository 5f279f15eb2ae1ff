// Atomic output (core/atomic_file.h): the whole file or nothing, and a symbolic link the user
// made is written through, not replaced.
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
