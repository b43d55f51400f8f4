// Rotor-speed lag (effects.md, actuator candidates). When a log holds the
// rotor-speed commands (no tachometer), the rotors reach them late: the
// applied omega1, omega2 follow the logged ones through first-order lags of
// time constants T_m1, T_m2, exactly as servo_lag does for the swashplate
// (dynamics/held_input.h). T = 0 is no lag. Flight only.
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct MotorLagEffect : EffectBase {
  static constexpr const char* kName = "motor_lag";
  static constexpr const char* kDescription =
      "rotor-speed lag: the applied omega1, omega2 follow the logged (commanded) speeds through "
      "first-order lags T_m1, T_m2 (the paper takes the logged speeds as the rotors' own)";
  // omega1 lags with p[0] = T_m1, omega2 with p[1] = T_m2.
  static constexpr std::array<int, 4> kInputLag = {0, 1, -1, -1};
  // Typical: a small brushless motor and rotor, 50-200 ms (the CoaX's 0.19 s
  // and 0.11 s, issue 17). Linearised at 2 ms, as servo_lag.
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"T_m1", 0.0, 0.0, 1.0, 5e-2, 0.08, "s", 2e-3},
        {"T_m2", 0.0, 0.0, 1.0, 5e-2, 0.06, "s", 2e-3}};
    return p;
  }
};

}  // namespace coaxid
