// Lower rotor in the upper rotor's wake. The paper uses one loss factor sigma
// for both rotors (eq. 12); measured coaxial pairs show the lower rotor losing
// far more. On top of sigma, the lower rotor's thrust magnitude falls by
// k_T omega1 omega2 (along its own axis, so its lateral components and the
// moments GO2 ^ T2 of eq. 30 fall with it) and its torque magnitude by
// k_Q omega1 omega2.
#pragma once

#include "core/parameters.h"
#include "dynamics/effects/effect.h"
#include "dynamics/sin_cos.h"

namespace coaxid {

struct WakeInterferenceEffect : EffectBase {
  static constexpr const char* kName = "wake_interference";
  static constexpr const char* kDescription =
      "lower rotor in the upper rotor's wake: thrust magnitude falls by k_T omega1 omega2, torque "
      "magnitude by k_Q omega1 omega2 (the paper has one sigma for both rotors, eq. 12)";
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"k_T", 0.0, 0.0, 1e-2, 5e-6, 5e-6, "N s^2"},
        {"k_Q", 0.0, 0.0, 1e-3, 1e-7, 1e-7, "N m s^2"}};
    return p;
  }
  template <typename T>
  static void AddLoads(const EffectContext<T>& c, const T* p, AeroLoads<T>* loads) {
    const T w12 = c.omega1 * c.omega2;
    // Unit vector of the lower rotor's thrust direction scaled by beta < 0
    // (eq. 9): n = (-sin dy cos dx, -sin dx, cos dx cos dy) points along T2 / beta,
    // so reducing the magnitude adds +k_T w12 n.
    T sx, cx, sy, cy;
    SinCos(c.delta_cx, &sx, &cx);
    SinCos(c.delta_cy, &sy, &cy);
    const Vec3<T> dT2 = (p[0] * w12) * Vec3<T>(-sy * cx, -sx, cx * cy);
    const T d = c.theta[kHubDistance];
    loads->force_B += dT2;
    loads->moment_B[0] += d * dT2[1];  // eq. 31: L = d T2_y
    loads->moment_B[1] -= d * dT2[0];  // eq. 32: M = -d T2_x
    loads->Z2 += dT2[2];
    // The lower rotor's torque gamma2 omega2^2 shrinks in magnitude.
    const T dN2 = c.theta[kGamma2] < T(0) ? p[1] * w12 : -p[1] * w12;
    loads->moment_B[2] += dN2;
    loads->N2 += dN2;
  }
};

}  // namespace coaxid
