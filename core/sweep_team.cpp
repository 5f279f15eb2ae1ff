#include "core/sweep_team.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace chordfit {
namespace {

// Busy-wait step: a pause instruction for the first spins (a class ends within microseconds),
// then a yield so that a waiting thread gives its core away on a loaded machine.
inline void backOff(int& spins) {
  if (++spins < 4096) {
#if defined(__x86_64__) || defined(__i386__)
    _mm_pause();
#endif
  } else {
    std::this_thread::yield();
  }
}

}  // namespace

SweepTeam::SweepTeam(int threads) {
  for (int part = 1; part < threads; ++part)
    helpers_.emplace_back([this, part] { helperLoop(part); });
}

SweepTeam::~SweepTeam() {
  stop_.store(true, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  for (std::thread& t : helpers_) t.join();
}

void SweepTeam::runErased(void* task, void (*call)(void*, int)) {
  if (helpers_.empty()) {
    call(task, 0);
    return;
  }
  task_ = task;
  call_ = call;
  pending_.store(static_cast<int>(helpers_.size()), std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);  // publishes task_, call_, pending_
  call(task, 0);
  int spins = 0;
  while (pending_.load(std::memory_order_acquire) != 0) backOff(spins);
}

void SweepTeam::helperLoop(int part) {
  unsigned seen = 0;
  for (;;) {
    unsigned now;
    int spins = 0;
    while ((now = generation_.load(std::memory_order_acquire)) == seen) backOff(spins);
    seen = now;
    if (stop_.load(std::memory_order_relaxed)) return;
    call_(task_, part);
    pending_.fetch_sub(1, std::memory_order_release);  // publishes this part's writes
  }
}

}  // namespace chordfit
