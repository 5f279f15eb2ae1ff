// A fixed team of threads for the simulator's colour-parallel constraint sweeps.
//
// A Gauss-Seidel sweep over one colour class (xpbd_constraints.h, orderByColour) touches every
// vertex at most once, so the class can be cut into contiguous parts projected at the same
// time with the same result, bit for bit, as projecting it in order. run() hands one part to
// each thread and returns when all are done: a barrier per class. A class lasts a few
// microseconds, so the helpers spin on an atomic counter rather than sleep on a condition
// variable (whose wake-up costs about as much as the class), and yield after a while so a
// busy machine is not starved.
#pragma once

#include <atomic>
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

  int threads() const { return static_cast<int>(helpers_.size()) + 1; }

  // Calls task(part) for part = 0 .. threads() - 1, part 0 on the calling thread, and returns
  // when every call has returned. task must not throw.
  template <class Task>
  void run(Task& task) {
    runErased(&task, [](void* t, int part) { (*static_cast<Task*>(t))(part); });
  }

 private:
  void runErased(void* task, void (*call)(void*, int));
  void helperLoop(int part);

  std::vector<std::thread> helpers_;
  std::atomic<unsigned> generation_{0};  // bumped once per run(); helpers wait for a change
  std::atomic<int> pending_{0};          // helpers still working on the current run
  std::atomic<bool> stop_{false};
  void* task_ = nullptr;  // written before generation_ is bumped
  void (*call_)(void*, int) = nullptr;
};

// The part [begin, end) of `part` when [0, count) is cut into `parts` contiguous pieces.
inline void partRange(int count, int parts, int part, int& begin, int& end) {
  begin = static_cast<int>(static_cast<long long>(count) * part / parts);
  end = static_cast<int>(static_cast<long long>(count) * (part + 1) / parts);
}

}  // namespace chordfit
