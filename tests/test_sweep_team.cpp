// The simulator's thread team (core/sweep_team.h): every part runs exactly once per run, the
// parts' writes are visible when run() returns, and the parts tile a range.
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/sweep_team.h"

namespace chordfit {
namespace {

TEST(SweepTeam, RunsEveryPartOncePerRunAndPublishesItsWrites) {
  for (const int threads : {1, 2, 3}) {
    SweepTeam team(threads);
    ASSERT_EQ(team.threads(), threads);
    std::vector<int> calls(threads, 0);  // plain ints: run() must order the writes
    long long sum = 0;
    for (int round = 0; round < 5000; ++round) {
      auto task = [&](int part) { ++calls[part]; };
      team.run(task);
      for (int part = 0; part < threads; ++part) sum += calls[part];
    }
    for (int part = 0; part < threads; ++part) EXPECT_EQ(calls[part], 5000) << part;
    EXPECT_EQ(sum, static_cast<long long>(threads) * 5000 * 5001 / 2);
  }
}

// A helper that keeps the caller waiting (here: the helper holds its part 20 ms, as a
// descheduled helper would) makes the team go alone after kMaxStalls such runs; every part
// still runs exactly once per run. The caller's part waits until the helper has claimed the
// other one, so the helper, not the caller, runs it.
TEST(SweepTeam, GoesAloneWhenTheCallerKeepsWaitingAndStillRunsEveryPart) {
  SweepTeam team(2);
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<int> calls(2, 0);
  int runs = 0;
  for (; runs < 300 && !team.alone(); ++runs) {
    std::atomic<bool> helper_started{false};
    auto task = [&](int part) {
      if (std::this_thread::get_id() != caller) {
        helper_started = true;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      } else {
        while (!helper_started) std::this_thread::yield();
      }
      ++calls[part];
    };
    team.run(task);
  }
  EXPECT_TRUE(team.alone()) << "after " << runs << " runs";
  EXPECT_EQ(team.threads(), 2) << "the parts per run do not change";
  for (int round = 0; round < 10; ++round) {
    auto task = [&](int part) { ++calls[part]; };
    team.run(task);
  }
  EXPECT_EQ(calls[0], runs + 10);
  EXPECT_EQ(calls[1], runs + 10);
}

TEST(SweepTeam, PartsTileTheRangeInOrder) {
  for (const int count : {0, 1, 7, 128, 1001})
    for (const int parts : {1, 2, 3}) {
      int expected_begin = 0;
      for (int part = 0; part < parts; ++part) {
        int begin, end;
        partRange(count, parts, part, begin, end);
        EXPECT_EQ(begin, expected_begin);
        EXPECT_LE(begin, end);
        EXPECT_LE(end - begin, count / parts + 1);
        expected_begin = end;
      }
      EXPECT_EQ(expected_begin, count);
    }
}

}  // namespace
}  // namespace chordfit
