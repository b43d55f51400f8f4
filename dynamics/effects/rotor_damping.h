// Rotor (flapping) damping of roll and pitch rates. The paper's moments come
// only from the swashplate (eqs. 31-32); a rotor disc tilting against the
// body's rotation damps it: L = -k_pq p, M = -k_pq q.
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct RotorDampingEffect : EffectBase {
  static constexpr const char* kName = "rotor_damping";
  static constexpr const char* kDescription =
      "rate damping L = -k_pq p, M = -k_pq q (the paper's moments come only from the swashplate)";
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"k_pq", 0.0, 0.0, 0.1, 1e-3, 2e-3, "N m s"}};
    return p;
  }
  template <typename T>
  static void AddLoads(const EffectContext<T>& c, const T* p, AeroLoads<T>* loads) {
    loads->moment_B[0] -= p[0] * c.w_B[0];
    loads->moment_B[1] -= p[0] * c.w_B[1];
  }
};

}  // namespace coaxid
