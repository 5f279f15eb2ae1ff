// The words of the command lines notes suggest (tools/shell_word.h): pasted into a POSIX
// shell, each reads back as the one argument it was.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "tools/shell_word.h"

namespace chordfit::cli {
namespace {

TEST(ShellWord, LeavesPlainPathsAsTheyAre) {
  EXPECT_EQ(shellWord("build/cases/prolapse-P2"), "build/cases/prolapse-P2");
  EXPECT_EQ(shellWord("/tmp/a_b/c.json"), "/tmp/a_b/c.json");
}

TEST(ShellWord, QuotesWhatAShellWouldSplitOrExpand) {
  EXPECT_EQ(shellWord("my case"), "'my case'");
  EXPECT_EQ(shellWord("$HOME/*.json"), "'$HOME/*.json'");
  EXPECT_EQ(shellWord("it's"), "'it'\\''s'");
  EXPECT_EQ(shellWord(""), "''") << "an empty argument stays one";
}

// What the shell makes of the quoted word is the word itself.
TEST(ShellWord, ReadsBackThroughAShell) {
  for (const std::string word : {"a b", "it's", "$x `y` \"z\"", "semi;colon&"}) {
    const std::string command = "printf %s " + shellWord(word);
    FILE* pipe = ::popen(command.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string back;
    for (int c; (c = std::fgetc(pipe)) != EOF;) back += static_cast<char>(c);
    ::pclose(pipe);
    EXPECT_EQ(back, word) << command;
  }
}

}  // namespace
}  // namespace chordfit::cli
