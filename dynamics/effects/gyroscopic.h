// Gyroscopic moment of the rotors. The paper (sect. 2.2) assumes the two
// rotors' moments "offset one another"; with unequal speeds they do not.
// omega1 spins about +z_b, omega2 about -z_b, so the rotor angular momentum is
// h = J_r (omega1 - omega2) along z_b, and w_B x h adds L = -q h, M = +p h.
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct GyroscopicEffect : EffectBase {
  static constexpr const char* kName = "gyroscopic";
  static constexpr const char* kDescription =
      "rotor angular momentum J_r (omega1 - omega2): L = -q h, M = +p h (the paper assumes the "
      "rotors' gyroscopic moments cancel, sect. 2.2)";
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"J_r", 0.0, 0.0, 1e-2, 1e-4, 1e-4, "kg m^2"}};
    return p;
  }
  template <typename T>
  static void AddLoads(const EffectContext<T>& c, const T* p, AeroLoads<T>* loads) {
    const T h = p[0] * (c.omega1 - c.omega2);
    loads->moment_B[0] -= c.w_B[1] * h;
    loads->moment_B[1] += c.w_B[0] * h;
  }
};

}  // namespace coaxid
