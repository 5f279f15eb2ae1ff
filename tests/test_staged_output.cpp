// The staging directory behind every command's output set (tools/staged_output.h): all or
// nothing, and only the file names the command declares (which its pre-flight checks).
#include <gtest/gtest.h>

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

TEST(StagedOutput, PublishesTheWrittenFilesInDeclaredOrderAndLeavesNoStaging) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  std::vector<std::string> published;
  {
    StagedOutput staged(out, {"a.txt", "b.txt", "c.txt"});
    writeText(staged.dir() / "c.txt", "c");
    writeText(staged.dir() / "a.txt", "a");
    EXPECT_FALSE(fs::exists(out / "a.txt"));  // nothing is visible before publishing
    published = staged.publish();
  }
  EXPECT_EQ(published, (std::vector<std::string>{"a.txt", "c.txt"}));
  EXPECT_EQ(readText(out / "a.txt"), "a");
  EXPECT_EQ(readText(out / "c.txt"), "c");
  EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator()), 2);
  EXPECT_EQ(wroteLine(out, published), "wrote " + (out / "a.txt").string() + ", c.txt");
}

TEST(StagedOutput, RemovesTheCommandsFilesThisRunDidNotWriteButNoDirectoryNorOtherFile) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  fs::create_directories(out / "d.txt");
  for (const char* name : {"a.txt", "b.txt", "old.txt", "mine.txt"})
    writeText(out / name, "earlier");
  {
    StagedOutput staged(out, {"a.txt", "b.txt", "d.txt"}, {"old.txt"});
    writeText(staged.dir() / "a.txt", "a");
    EXPECT_EQ(staged.publish(), std::vector<std::string>{"a.txt"});
  }
  EXPECT_EQ(readText(out / "a.txt"), "a");
  EXPECT_FALSE(fs::exists(out / "b.txt")) << "declared, not written: an earlier run's";
  EXPECT_FALSE(fs::exists(out / "old.txt")) << "superseded";
  EXPECT_TRUE(fs::is_directory(out / "d.txt")) << "a directory is never removed";
  EXPECT_EQ(readText(out / "mine.txt"), "earlier") << "not the command's";
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
  EXPECT_TRUE(fs::is_empty(out));  // the staging directory is gone, nothing was moved
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

}  // namespace
}  // namespace chordfit::cli
