#include "dynamics/state.h"

#include <glog/logging.h>

namespace coaxid {

const char* StateName(int index) {
  static constexpr const char* kNames[kNumStates] = {"x",   "y",     "z",   "u", "v", "w",
                                                     "phi", "theta", "psi", "p", "q", "r"};
  CHECK(index >= 0 && index < kNumStates) << index;
  return kNames[index];
}

}  // namespace coaxid
