#include "core/sweep_team.h"

#include <algorithm>
#include <chrono>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace chordfit {
namespace {

using Clock = std::chrono::steady_clock;

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

SweepTeam::SweepTeam(int threads) : parts_(std::max(1, threads)) {
  for (int part = 1; part < parts_; ++part) helpers_.emplace_back([this] { helperLoop(); });
}

SweepTeam::~SweepTeam() { stopHelpers(); }

void SweepTeam::stopHelpers() {
  stop_.store(true, std::memory_order_relaxed);
  const std::uint64_t next = (state_.load(std::memory_order_relaxed) >> 32) + 1;
  // A new generation with every part taken: the helpers wake, claim nothing, see stop_.
  state_.store(next << 32 | static_cast<std::uint64_t>(parts_), std::memory_order_release);
  for (std::thread& t : helpers_) t.join();
  helpers_.clear();
}

void SweepTeam::runErased(void* task, void (*call)(void*, int)) {
  if (helpers_.empty()) {  // one thread, or gone alone: the parts in order
    for (int part = 0; part < parts_; ++part) call(task, part);
    return;
  }
  task_ = task;
  call_ = call;
  done_.store(0, std::memory_order_relaxed);
  const unsigned generation =
      static_cast<unsigned>(state_.load(std::memory_order_relaxed) >> 32) + 1;
  const auto start = Clock::now();
  // Publishes task_, call_ and done_ with the run: part 0 is the next to claim.
  state_.store(static_cast<std::uint64_t>(generation) << 32, std::memory_order_release);
  claimParts(generation);
  const auto own_done = Clock::now();
  int spins = 0;
  while (done_.load(std::memory_order_acquire) != parts_) backOff(spins);
  const double own = std::chrono::duration<double>(own_done - start).count();
  const double waited = std::chrono::duration<double>(Clock::now() - own_done).count();
  if (waited > kStallSeconds && waited > 2.0 * own && ++stalls_ >= kMaxStalls) {
    stopHelpers();
    alone_ = true;
  }
}

void SweepTeam::claimParts(unsigned generation) {
  const std::uint64_t parts = static_cast<std::uint64_t>(parts_);
  std::uint64_t s = state_.load(std::memory_order_acquire);
  for (;;) {
    if (static_cast<unsigned>(s >> 32) != generation || (s & 0xffffffffu) >= parts) return;
    // On failure s is reloaded: another thread claimed this part, or a new run began.
    if (!state_.compare_exchange_weak(s, s + 1, std::memory_order_acq_rel,
                                      std::memory_order_acquire))
      continue;
    call_(task_, static_cast<int>(s & 0xffffffffu));
    done_.fetch_add(1, std::memory_order_release);  // publishes the part's writes
    s = state_.load(std::memory_order_acquire);
  }
}

void SweepTeam::helperLoop() {
  unsigned seen = 0;
  for (;;) {
    unsigned generation;
    int spins = 0;
    while ((generation = static_cast<unsigned>(state_.load(std::memory_order_acquire) >> 32)) ==
           seen)
      backOff(spins);
    seen = generation;
    if (stop_.load(std::memory_order_relaxed)) return;
    claimParts(generation);
  }
}

}  // namespace chordfit
