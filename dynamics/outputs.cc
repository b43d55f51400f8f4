#include "dynamics/outputs.h"

#include <glog/logging.h>

namespace coaxid {
namespace {
constexpr const char* kBalanceNames[kNumBalanceChannels] = {"X",  "Y",  "Z",  "L",  "M",
                                                            "N",  "Z1", "Z2", "N1", "N2"};
}  // namespace

const char* FlightChannelName(int channel) {
  CHECK(channel >= 0 && channel < kNumFlightChannels) << channel;
  if (channel < kNumStates) return StateName(channel);
  static constexpr const char* kAccel[3] = {"ax", "ay", "az"};
  return kAccel[channel - kNumStates];
}

const char* BalanceChannelName(int channel) {
  CHECK(channel >= 0 && channel < kNumBalanceChannels) << channel;
  return kBalanceNames[channel];
}

int FlightChannelIndex(const std::string& column) {
  for (int i = 0; i < kNumFlightChannels; ++i) {
    if (column == FlightChannelName(i)) return i;
  }
  return -1;
}

int BalanceChannelIndex(const std::string& column) {
  for (int i = 0; i < kNumBalanceChannels; ++i) {
    if (column == kBalanceNames[i]) return i;
  }
  return -1;
}

}  // namespace coaxid
