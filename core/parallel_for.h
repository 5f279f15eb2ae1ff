// Independent tasks on a few threads: the fit's finite differences and pre-fit grids, the
// sweep over a cord's scale.
#pragma once

#include <functional>

namespace chordfit {

// Runs task(i) for i in [0, count) on `threads` threads (work stealing by an atomic counter).
// The tasks must write only to their own slots. An exception thrown by a task is rethrown to
// the caller after every thread has stopped: that of the lowest task index, as with one thread.
void parallelFor(int count, int threads, const std::function<void(int)>& task);

}  // namespace chordfit
