// Swashplate trim error: the servos do not hold exactly the logged angles.
// delta_cx + b_x and delta_cy + b_y replace the logged angles everywhere
// (thrust, moments, wake speed).
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct SwashplateBiasEffect : EffectBase {
  static constexpr const char* kName = "swashplate_bias";
  static constexpr const char* kDescription =
      "servo trim error: delta_cx + b_x, delta_cy + b_y replace the logged angles (the paper "
      "takes the logged angles as exact)";
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"b_x", 0.0, -0.2, 0.2, 1e-2, 0.015, "rad"},
        {"b_y", 0.0, -0.2, 0.2, 1e-2, -0.01, "rad"}};
    return p;
  }
  template <typename T>
  static void AdjustInputs(const T* p, T* delta_cx, T* delta_cy) {
    *delta_cx += p[0];
    *delta_cy += p[1];
  }
};

}  // namespace coaxid
