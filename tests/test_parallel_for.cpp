// parallelFor (core/parallel_for.h): every task runs once, and an exception thrown by
// a task reaches the caller (not std::terminate), the lowest task index's one for any number of
// threads.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/parallel_for.h"

namespace chordfit {
namespace {

TEST(ParallelFor, RunsEveryTaskOnce) {
  for (int threads : {1, 2, 4}) {
    std::vector<std::atomic<int>> runs(100);
    parallelFor(100, threads, [&](int i) { ++runs[i]; });
    for (int i = 0; i < 100; ++i) EXPECT_EQ(runs[i], 1) << "task " << i << ", " << threads;
  }
}

TEST(ParallelFor, RethrowsTheFailureOfTheLowestTaskToTheCaller) {
  for (int threads : {1, 2, 4}) {
    try {
      parallelFor(50, threads, [](int i) {
        if (i == 7 || i == 31) throw std::runtime_error("task " + std::to_string(i));
      });
      ADD_FAILURE() << "no exception with " << threads << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "task 7") << threads << " threads";
    }
  }
}

// A higher task failing first (sweep-cord's points run out of order on two threads): the tasks
// below it still run, the lower failure that comes later is the one rethrown, and no task
// above the first failure starts after it.
TEST(ParallelFor, AHigherTaskFailingFirstStillReportsTheLowerFailureAndStopsAboveIt) {
  std::vector<std::atomic<int>> runs(50);
  std::atomic<bool> task3_failed{false};
  try {
    parallelFor(50, 2, [&](int i) {
      ++runs[i];
      if (i == 0) {
        // Task 0 fails last: it waits (at most 10 s) until the other thread's task 3 has failed.
        for (int k = 0; k < 10000 && !task3_failed; ++k)
          std::this_thread::sleep_for(std::chrono::milliseconds(1));
        throw std::runtime_error("task 0");
      }
      if (i == 3) {
        task3_failed = true;
        throw std::runtime_error("task 3");
      }
    });
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "task 0");
  }
  for (int i = 0; i <= 3; ++i) EXPECT_EQ(runs[i], 1) << "task " << i;
  for (int i = 4; i < 50; ++i) EXPECT_EQ(runs[i], 0) << "task " << i << " ran after task 3 failed";
}

}  // namespace
}  // namespace chordfit
