// parallelFor (core/parallel_for.h): every task runs once, and an exception thrown by
// a task reaches the caller (not std::terminate), the lowest task index's one for any number of
// threads.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
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

}  // namespace
}  // namespace chordfit
