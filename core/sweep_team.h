// A fixed team of threads for the simulator's colour-parallel constraint sweeps.
//
// A Gauss-Seidel sweep over one colour class (xpbd_constraints.h, orderByColour) touches every
// vertex at most once, so the class can be cut into contiguous parts projected at the same
// time with the same result, bit for bit, as projecting it in order. run() offers the parts to
// the team and returns when all are done: a barrier per class. A class lasts a few
// microseconds, so the helpers spin on an atomic counter rather than sleep on a condition
// variable (whose wake-up costs about as much as the class), and yield after a while.
//
// Parts are claimed, not assigned: the calling thread claims parts too, so a helper that the
// operating system has descheduled (a machine busier than its cores) is not waited for unless
// it had already started a part. Which thread runs a part does not change the result. When
// the caller still waits long for helpers, run after run (kMaxStalls times: a machine with
// more runnable threads than cores, where a spinning team is slower than one thread), the
// helpers are stopped and the calling thread runs every part itself from then on.
#pragma once

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace chordfit {

class SweepTeam {
 public:
  // threads >= 1: the calling thread plus threads - 1 helpers, started here.
  explicit SweepTeam(int threads);
  ~SweepTeam();
  SweepTeam(const SweepTeam&) = delete;
  SweepTeam& operator=(const SweepTeam&) = delete;

  // Parts per run (the thread count asked for), also after the team has gone alone.
  int threads() const { return parts_; }
  // True once the helpers were stopped for waiting too long (see above).
  bool alone() const { return alone_; }

  // Calls task(part) once for each part = 0 .. threads() - 1, on whichever thread claims it
  // (the calling thread included), and returns when every call has returned. task must not
  // throw.
  template <class Task>
  void run(Task& task) {
    runErased(&task, [](void* t, int part) { (*static_cast<Task*>(t))(part); });
  }

 private:
  void runErased(void* task, void (*call)(void*, int));
  void helperLoop();
  // Claims and runs unclaimed parts of run `generation` until none is left.
  void claimParts(unsigned generation);
  // Stops and joins the helpers.
  void stopHelpers();

  // A wait for helpers counts as a stall when it exceeds both this and twice the caller's own
  // share of the run (an idle machine's runs stay far below: parts differ by tens of percent).
  static constexpr double kStallSeconds = 50e-6;
  static constexpr int kMaxStalls = 100;

  const int parts_;
  bool alone_ = false;  // the calling thread runs every part (caller-only state)
  int stalls_ = 0;
  std::vector<std::thread> helpers_;
  // generation << 32 | the next unclaimed part; a new run bumps the generation and resets the
  // part to 0 in one store, so a late helper cannot claim a part of a run that has ended.
  std::atomic<std::uint64_t> state_{0};
  std::atomic<int> done_{0};  // parts of the current run finished
  std::atomic<bool> stop_{false};
  void* task_ = nullptr;  // written before the run is published in state_
  void (*call_)(void*, int) = nullptr;
};

// The part [begin, end) of `part` when [0, count) is cut into `parts` contiguous pieces.
inline void partRange(int count, int parts, int part, int& begin, int& end) {
  begin = static_cast<int>(static_cast<long long>(count) * part / parts);
  end = static_cast<int>(static_cast<long long>(count) * (part + 1) / parts);
}

}  // namespace chordfit
