// Constant wind. The paper sets V_wind = 0; a steady wind (wn, we, wd) in
// earth (NED) axes, rotated into body axes, enters the total airflow of
// eqs. 43-45 and so the body force (eq. 24).
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct WindEffect : EffectBase {
  static constexpr const char* kName = "wind";
  static constexpr const char* kDescription =
      "constant wind (wn, we, wd) in earth axes entering the body airflow, eqs. 43-45 (the "
      "paper sets V_wind = 0)";
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"wn", 0.0, -15.0, 15.0, 1.0, 2.0, "m/s"},
        {"we", 0.0, -15.0, 15.0, 1.0, -1.5, "m/s"},
        {"wd", 0.0, -15.0, 15.0, 1.0, 0.0, "m/s"}};
    return p;
  }
  template <typename T>
  static void AddWindEarth(const T* p, Vec3<T>* wind_E) {
    (*wind_E)[0] += p[0];
    (*wind_E)[1] += p[1];
    (*wind_E)[2] += p[2];
  }
};

}  // namespace coaxid
