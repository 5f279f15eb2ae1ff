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
  // error message, leaving its staging directory): each worker catches, the others stop taking
  // tasks, and the exception of the lowest task index is rethrown here (the same one for any
  // thread count, as with one thread).
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  std::mutex mutex;
  int failed_task = count;
  std::exception_ptr failure;
  auto work = [&] {
    for (int i = next++; i < count && !failed; i = next++) {
      try {
        task(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (i < failed_task) {
          failed_task = i;
          failure = std::current_exception();
        }
        failed = true;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < workers; ++t) pool.emplace_back(work);
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace chordfit
