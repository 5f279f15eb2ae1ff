#include "core/parallel_for.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace chordfit {

void parallelFor(int count, int threads, const std::function<void(int)>& task) {
  const int workers = std::max(1, std::min(threads, count));
  if (workers == 1) {
    for (int i = 0; i < count; ++i) task(i);
    return;
  }
  // An exception escaping a std::thread calls std::terminate (the process dies without its
  // error message, leaving its staging directory): each worker catches, and the exception of
  // the lowest failing task is rethrown here, the same one for any thread count, as with one
  // thread. After a failure only tasks below it still run (one of them may fail too).
  std::atomic<int> next{0}, lowest_failed{count};
  std::mutex mutex;
  std::exception_ptr failure;
  auto work = [&] {
    for (int i = next++; i < count; i = next++) {
      if (i > lowest_failed.load()) continue;
      try {
        task(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (i < lowest_failed.load()) {
          lowest_failed = i;
          failure = std::current_exception();
        }
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < workers; ++t) pool.emplace_back(work);
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace chordfit
