// Accelerometer bias (effects.md, measurement candidates). The model's
// accelerometer reads the specific force exactly (model.md, decision 7); a
// real one adds a constant offset per axis: logged ax, ay, az = true +
// (b_ax, b_ay, b_az). The dynamics do not change.
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct AccelBiasEffect : EffectBase {
  static constexpr const char* kName = "accel_bias";
  static constexpr const char* kDescription =
      "accelerometer bias: logged ax, ay, az = true + (b_ax, b_ay, b_az) (the model takes the "
      "accelerometer as exact)";
  static constexpr bool kChangesFlightMeasurements = true;
  // Typical: a consumer MEMS accelerometer's offset, 0.1-0.2 m/s^2.
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"b_ax", 0.0, -2.0, 2.0, 0.1, 0.15, "m/s^2"},
        {"b_ay", 0.0, -2.0, 2.0, 0.1, -0.1, "m/s^2"},
        {"b_az", 0.0, -2.0, 2.0, 0.1, 0.2, "m/s^2"}};
    return p;
  }
  template <typename T>
  static void AddToFlightMeasurements(const T* p, T* y) {
    y[kAx] += p[0];
    y[kAy] += p[1];
    y[kAz] += p[2];
  }
};

}  // namespace coaxid
