// The progress lines of long fit stages (inverse/finite_difference.h closureHeartbeat): none
// on a stage shorter than the interval, none for the last closure (the stage's own line
// follows), and thread-safe.
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "inverse/finite_difference.h"

namespace chordfit::inverse {
namespace {

TEST(ClosureHeartbeat, SaysWhatIsRunningAfterTheIntervalButNotForTheLastClosure) {
  std::vector<std::string> said;
  auto every_time =
      closureHeartbeat([&](const std::string& line) { said.push_back(line); }, "jacobian", 0.0);
  for (int done = 1; done <= 3; ++done) every_time(done, 3);
  ASSERT_EQ(said.size(), 2u);
  EXPECT_EQ(said[0].rfind("jacobian: 1 of 3 closures, ", 0), 0u) << said[0];
  EXPECT_EQ(said[1].rfind("jacobian: 2 of 3 closures, ", 0), 0u) << said[1];

  said.clear();
  auto rarely =
      closureHeartbeat([&](const std::string& line) { said.push_back(line); }, "jacobian", 3600.0);
  for (int done = 1; done <= 50; ++done) rarely(done, 50);
  EXPECT_TRUE(said.empty()) << "a stage shorter than the interval prints nothing";

  EXPECT_FALSE(closureHeartbeat(nullptr, "jacobian")) << "nowhere to say it: no callback";
}

// A stage of several batches counts its closures across them (a count per batch read
// "1 of 5 closures" after 20 of them).
TEST(ClosureHeartbeat, AStageCountsItsClosuresAcrossBatches) {
  std::vector<std::string> said;
  auto beat =
      stageHeartbeat([&](const std::string& line) { said.push_back(line); }, "pre-fit", 0.0);
  for (int batch = 0; batch < 3; ++batch)
    for (int done = 1; done <= 5; ++done) beat(done, 5);
  ASSERT_EQ(said.size(), 15u);
  EXPECT_EQ(said.back().rfind("pre-fit: 15 closures so far, ", 0), 0u) << said.back();
}

TEST(ClosureHeartbeat, TakesCallsFromSeveralThreads) {
  int said = 0;  // guarded by the heartbeat's own lock
  auto beat = closureHeartbeat([&](const std::string&) { ++said; }, "pre-fit", 0.0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&beat, t] {
      for (int k = 0; k < 250; ++k) beat(1 + t * 250 + k, 2000);
    });
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(said, 1000);
}

}  // namespace
}  // namespace chordfit::inverse
