// Rotor drag (H-force). The paper neglects body-motion airflow against the
// rotor wake (V_prop >> V_body, eq. 29); a translating rotor feels a drag
// proportional to its speed: X = -k_h (omega1 + omega2) u,
// Y = -k_h (omega1 + omega2) v, with the ground-relative u, v.
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct RotorDragEffect : EffectBase {
  static constexpr const char* kName = "rotor_drag";
  static constexpr const char* kDescription =
      "rotor H-force X = -k_h (omega1 + omega2) u, Y = -k_h (omega1 + omega2) v (the paper "
      "assumes V_prop >> V_body, eq. 29)";
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"k_h", 0.0, 0.0, 1e-2, 3e-4, 3e-4, "N s^2/m"}};
    return p;
  }
  template <typename T>
  static void AddLoads(const EffectContext<T>& c, const T* p, AeroLoads<T>* loads) {
    const T k = p[0] * (c.omega1 + c.omega2);
    loads->force_B[0] -= k * c.v_B[0];
    loads->force_B[1] -= k * c.v_B[1];
  }
};

}  // namespace coaxid
