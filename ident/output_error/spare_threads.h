// Threads that fits run side by side have finished with, lent to the fits
// still running.
//
// discover restarts a fit from several points at once, each on its share of
// the cores (ident/discover/round_refits.h, SideBySide). The restarts end at
// different times, and an odd batch (three restarts on two cores) leaves one
// core idle for the whole of its last restart. A worker that runs out of
// restarts adds its threads here; every segment evaluation of a fit still
// running (ParallelSegmentEvaluation) borrows what is idle for that
// evaluation and gives it back. Lending changes no result: each segment is
// the same whichever thread computes it, and Ceres reads them in its own
// order (parallel_segments.h).
#pragma once

#include <algorithm>
#include <atomic>

namespace coaxid {

class SpareThreads {
 public:
  // Threads a worker no longer needs.
  void Add(int n) {
    if (n > 0) idle_ += n;
  }
  // Up to at_most idle threads (0 if none); give them back with Return.
  int Borrow(int at_most) {
    int idle = idle_.load();
    while (idle > 0 && at_most > 0) {
      const int take = std::min(idle, at_most);
      if (idle_.compare_exchange_weak(idle, idle - take)) {
        lent_ += take;
        return take;
      }
    }
    return 0;
  }
  void Return(int n) { Add(n); }
  int idle() const { return idle_.load(); }
  // Threads lent so far, summed over the borrows.
  long lent() const { return lent_.load(); }

 private:
  std::atomic<int> idle_{0};
  std::atomic<long> lent_{0};
};

}  // namespace coaxid
