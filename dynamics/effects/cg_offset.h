// Centre of gravity off the rotor axis. The paper puts G on the shaft; if the
// shaft passes at (x_g, y_g) from G in body axes, the rotor z-force Z_T
// (eq. 13) makes a moment: L += y_g Z_T, M -= x_g Z_T.
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct CgOffsetEffect : EffectBase {
  static constexpr const char* kName = "cg_offset";
  static constexpr const char* kDescription =
      "rotor shaft at (x_g, y_g) from G: L += y_g Z_T, M -= x_g Z_T (the paper puts G on the "
      "rotor axis)";
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"x_g", 0.0, -0.05, 0.05, 5e-3, 4e-3, "m"},
        {"y_g", 0.0, -0.05, 0.05, 5e-3, -3e-3, "m"}};
    return p;
  }
  template <typename T>
  static void AddLoads(const EffectContext<T>& c, const T* p, AeroLoads<T>* loads) {
    loads->moment_B[0] += p[1] * c.rotor_z;
    loads->moment_B[1] -= p[0] * c.rotor_z;
  }
};

}  // namespace coaxid
