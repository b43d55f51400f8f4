// How many threads "every core" means: what the machine reports
// (std::thread::hardware_concurrency), at least 1 (it answers 0 when it
// cannot tell).
#pragma once

#include <algorithm>
#include <thread>

namespace coaxid {

inline int NumCores() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

}  // namespace coaxid
