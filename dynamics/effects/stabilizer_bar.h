// The stabilizer (fly)bar of the upper rotor (effects.md, stabilizer_bar):
// most small coaxial helicopters carry one; the paper's GLMAV does not, and
// its model keeps both rotor planes square to the shaft. The first effect
// with states of its own: the bar's tilt relative to the body, b_x (about
// x_b) and b_y (about y_b). The bar holds its orientation in space and
// relaxes toward the shaft with time constant T_b:
//   db_x/dt = -p - b_x / T_b,   db_y/dt = -q - b_y / T_b,
// b = 0 at the start of a simulation (at rest, aligned with the shaft).
// The upper rotor's plane follows the bar through the linkage factor k_b,
// tilting its thrust T1 = -sigma alpha omega1^2 > 0 (eq. 13): with the upper
// hub d_u above G (z_b down),
//   X = -k_b b_y T1,  Y = +k_b b_x T1,  L = d_u Y,  M = -d_u X
// (r x F with r = (0, 0, -d_u)). A pitch-up rate q > 0 leaves the bar
// behind (b_y < 0), so X > 0 and M < 0: the bar damps the motion, with a lag.
// k_b = 0 is no bar. Flight only: a balance holds the body still, so the bar
// rests aligned with the shaft.
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

struct StabilizerBarEffect : EffectBase {
  static constexpr const char* kName = "stabilizer_bar";
  static constexpr const char* kDescription =
      "stabilizer bar on the upper rotor: the bar's tilt (two states, relaxing toward the shaft "
      "with T_b) tilts the upper rotor's thrust by k_b, at the upper hub d_u above G (the paper "
      "keeps the rotor planes square to the shaft)";
  static constexpr int kNumOwnStates = 2;
  static std::vector<std::string> OwnStateNames() { return {"b_x", "b_y"}; }  // rad
  // Typical: the Skybotix CoaX (bar time constant about 1.8 s; linkage 0.61
  // in the public CoaX simulator's parameters; upper hub 0.165 m above G).
  // k_b is linearised at 0.05, beside absence: at k_b = 0 the outputs do not
  // depend on T_b or d_u, and the closing loop's score would see one
  // direction of three.
  static const std::vector<EffectParameterSpec>& Parameters() {
    static const std::vector<EffectParameterSpec> p = {
        {"T_b", 1.0, 0.05, 10.0, 1.0, 1.8, "s"},
        {"k_b", 0.0, 0.0, 2.0, 0.5, 0.6, "", 0.05},
        {"d_u", 0.15, 0.0, 0.5, 0.15, 0.165, "m"}};
    return p;
  }
  template <typename T>
  static void OwnStateDerivative(const T* p, const T* x, const T* s, T* sdot) {
    sdot[0] = -x[kP] - s[0] / p[0];
    sdot[1] = -x[kQ] - s[1] / p[0];
  }
  template <typename T>
  static void AddLoads(const EffectContext<T>& c, const T* p, AeroLoads<T>* loads) {
    if (c.own_states == nullptr) return;  // balance: the bar rests on the shaft
    const T T1 = -loads->Z1;              // upper rotor thrust magnitude, eq. 13
    const T X = -p[1] * c.own_states[1] * T1;
    const T Y = p[1] * c.own_states[0] * T1;
    loads->force_B[0] += X;
    loads->force_B[1] += Y;
    loads->moment_B[0] += p[2] * Y;
    loads->moment_B[1] -= p[2] * X;
  }
};

}  // namespace coaxid
