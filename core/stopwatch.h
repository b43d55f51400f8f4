// Wall time for progress lines and the timings reports carry: seconds on the
// steady clock since a start point.
#pragma once

#include <chrono>

namespace coaxid {

// Seconds elapsed since `start` (std::chrono::steady_clock).
inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace coaxid
