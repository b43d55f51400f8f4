// The library of candidate effects (../shared/spec/effects.md). To add an
// effect: write one header in this folder (see effect.h) and add its type to
// EffectTypes below. Everything else (configs, the model, reports, the
// closing loop) finds it by name from here.
#pragma once

#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "dynamics/effects/accel_bias.h"
#include "dynamics/effects/cg_offset.h"
#include "dynamics/effects/gyroscopic.h"
#include "dynamics/effects/ground_effect.h"
#include "dynamics/effects/gyro_bias.h"
#include "dynamics/effects/motor_lag.h"
#include "dynamics/effects/rotor_damping.h"
#include "dynamics/effects/rotor_drag.h"
#include "dynamics/effects/servo_lag.h"
#include "dynamics/effects/stabilizer_bar.h"
#include "dynamics/effects/swashplate_bias.h"
#include "dynamics/effects/wake_interference.h"
#include "dynamics/effects/wind.h"

namespace coaxid {

using EffectTypes =
    std::tuple<GyroscopicEffect, RotorDampingEffect, GroundEffect, RotorDragEffect,
               CgOffsetEffect, SwashplateBiasEffect, WindEffect, WakeInterferenceEffect,
               GyroBiasEffect, AccelBiasEffect, ServoLagEffect, MotorLagEffect,
               StabilizerBarEffect>;
inline constexpr int kNumEffects = std::tuple_size_v<EffectTypes>;

namespace internal {
template <typename F, std::size_t... I>
void ForEachEffectType(F&& f, std::index_sequence<I...>) {
  (f(std::tuple_element_t<I, EffectTypes>{}, static_cast<int>(I)), ...);
}
template <std::size_t... I>
constexpr int SumOfOwnStates(std::index_sequence<I...>) {
  return (0 + ... + std::tuple_element_t<I, EffectTypes>::kNumOwnStates);
}
}  // namespace internal

// The most states a model can have: the 12 rigid-body states and every
// library effect's own (fixed-capacity storage for the EKF's state blocks).
inline constexpr int kMaxModelStates =
    kNumStates + internal::SumOfOwnStates(std::make_index_sequence<kNumEffects>{});

// Calls f(EffectType{}, index) for every effect in the library, in order.
template <typename F>
void ForEachEffectType(F&& f) {
  internal::ForEachEffectType(f, std::make_index_sequence<kNumEffects>{});
}

struct EffectInfo {
  std::string name;
  std::string description;
  std::vector<EffectParameterSpec> parameters;
  int num_own_states = 0;  // states it adds after the 12 (stabilizer_bar: 2)
  std::vector<std::string> own_state_names;  // without the effect's prefix ("b_x", "b_y")
};

// Name, description and parameters of every effect, in library order.
const std::vector<EffectInfo>& EffectLibrary();
// Index in the library, or -1.
int EffectIndex(const std::string& name);

}  // namespace coaxid
