// Rate-gyro bias (effects.md, measurement candidates). The paper's model logs
// the true body rates; a MEMS gyro reads them with a constant offset:
// logged p, q, r = true + (b_p, b_q, b_r). The dynamics do not change.
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct GyroBiasEffect : EffectBase {
  static constexpr const char* kName = "gyro_bias";
  static constexpr const char* kDescription =
      "rate-gyro bias: logged p, q, r = true + (b_p, b_q, b_r) (the model takes the logged rates "
      "as the true ones)";
  static constexpr bool kChangesFlightMeasurements = true;
  // Typical: a consumer MEMS gyro's turn-on bias, about 1 deg/s (0.017 rad/s).
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"b_p", 0.0, -0.5, 0.5, 1e-2, 0.02, "rad/s"},
        {"b_q", 0.0, -0.5, 0.5, 1e-2, -0.015, "rad/s"},
        {"b_r", 0.0, -0.5, 0.5, 1e-2, 0.01, "rad/s"}};
    return p;
  }
  template <typename T>
  static void AddToFlightMeasurements(const T* p, T* y) {
    y[kP] += p[0];
    y[kQ] += p[1];
    y[kR] += p[2];
  }
};

}  // namespace coaxid
