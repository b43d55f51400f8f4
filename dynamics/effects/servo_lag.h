// Swashplate servo lag (effects.md, actuator candidates). A log holds the
// swashplate angles the flight computer commanded; the servos reach them
// late. The applied angles follow the logged ones through a first-order lag,
//   d(delta_a)/dt = (delta_logged - delta_a) / T_s,
// delta_a = delta_logged at a log's first row. The logged value holds between
// rows (model.md), so delta_a is an exact exponential inside each row
// interval (dynamics/held_input.h); T_s = 0 is no lag. Flight only: a balance
// hold lasts many T_s and the balance model is static.
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct ServoLagEffect : EffectBase {
  static constexpr const char* kName = "servo_lag";
  static constexpr const char* kDescription =
      "swashplate servo lag: the applied angles follow the logged (commanded) ones through a "
      "first-order lag of time constant T_s (the paper takes the logged angles as applied)";
  // Both swashplate angles lag with p[0] = T_s.
  static constexpr std::array<int, 4> kInputLag = {-1, -1, 0, 0};
  // Typical: a hobby-class digital servo under a swashplate load, 30-60 ms.
  // Linearised at 2 ms: at T_s = 0 the lag has no derivative (e^(-t/T_s)).
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"T_s", 0.0, 0.0, 0.5, 2e-2, 0.04, "s", 2e-3}};
    return p;
  }
};

}  // namespace coaxid
