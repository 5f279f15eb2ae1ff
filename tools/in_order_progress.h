// Progress lines of independent work items run in parallel (parallelFor), printed in item
// order whatever the order they finish in: an item's line comes once every item before it has
// had its own, so the terminal reads the same for any thread count (sweep-cord's scales,
// compare's cord sets).
#pragma once

#include <functional>
#include <mutex>
#include <vector>

namespace chordfit::cli {

class InOrderProgress {
 public:
  // `print(i)`: prints item i's line; false when nothing after it is to be printed (the run
  // stops at its lowest failing item).
  InOrderProgress(int count, std::function<bool(int)> print)
      : finished_(count, 0), print_(std::move(print)) {}

  // Item i has finished (from any thread): prints every line now due.
  void finished(int i) {
    const std::lock_guard<std::mutex> lock(mutex_);
    finished_[i] = 1;
    const int count = static_cast<int>(finished_.size());
    for (; next_ < count && finished_[next_]; ++next_) {
      if (!print_(next_)) {
        next_ = count;
        return;
      }
    }
  }

  // Runs `say` (another line, e.g. an item starting) without interleaving with the others.
  void say(const std::function<void()>& line) {
    const std::lock_guard<std::mutex> lock(mutex_);
    line();
  }

 private:
  std::mutex mutex_;
  std::vector<char> finished_;
  int next_ = 0;  // the first item whose line is not printed yet
  std::function<bool(int)> print_;
};

}  // namespace chordfit::cli
