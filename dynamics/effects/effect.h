// The effect interface: a physically named addition to the forces and
// moments of the paper's model (../shared/spec/effects.md), written once for
// any scalar type like the base model.
//
// An effect is a struct with
//   static constexpr const char* kName;           // the name used in configs/reports
//   static constexpr const char* kDescription;    // what the paper assumed away
//   static const std::vector<EffectParameterSpec>& Parameters();
// and any of these static member templates (EffectBase supplies no-op defaults):
//   AdjustInputs(p, &delta_cx, &delta_cy)   replace the logged swashplate angles
//   AddWindEarth(p, &wind_E)                 add to the wind in earth axes (eqs. 43-45)
//   AddLoads(context, p, &loads)             add forces and moments
//   AddToFlightMeasurements(p, y)            change what a flight log's sensors read
//                                            (y: the 15 flight channels of
//                                            dynamics/outputs.h, true values in, logged
//                                            values out); such an effect also sets
//                                            kChangesFlightMeasurements = true
// An effect that owns states (stabilizer_bar) sets kNumOwnStates > 0 and defines
//   OwnStateDerivative(p, x, s, sdot)        its states' derivative, flight only (x: the
//                                            whole state, s: its own states within it)
// and reads its states in AddLoads through context.own_states (nullptr in the balance
// setting, where they rest at zero). They follow the 12 rigid-body states in
// the state vector, in library order (VehicleModel::NumStates()), start at 0
// in simulations and are estimated like the others where estimators carry them.
// and an actuator effect (servo_lag, motor_lag) sets kInputLag: for each input (omega1,
// omega2, delta_cx, delta_cy) the index in p of the time constant of the
// first-order lag through which the applied input follows the logged one, or
// -1 (dynamics/held_input.h applies the lag, in flight).
// where p points at the effect's own parameters (in Parameters() order).
// Register it in effect_library.h.
#pragma once

#include <array>
#include <limits>
#include <string>
#include <vector>

#include "dynamics/state.h"

namespace coaxid {

struct EffectParameterSpec {
  std::string name;     // without the "effect." prefix
  double value;         // default: the value that makes the effect absent or physical
  double lower, upper;  // bounds for estimation
  double scale;         // typical magnitude, for scaling
  double typical;       // a clearly visible but realistic strength, for simulations
  std::string unit;
  // Where the closing loop linearises a candidate's parameter (NaN: at
  // `value`). Needed where the model has no derivative at absence: a lag's
  // response e^(-t/T) has none at T = 0.
  double linearise_at = std::numeric_limits<double>::quiet_NaN();
};

enum class Setting { kBalance, kFlight };

// Aerodynamic loads in body axes (no gravity): what a balance measures
// (model.md, decision 5) and what drives the 6-DoF model with gravity added.
template <typename T>
struct AeroLoads {
  Vec3<T> force_B;   // X, Y, Z [N]
  Vec3<T> moment_B;  // L, M, N [N m]
  T Z1, Z2;          // z-force of the upper / lower rotor alone [N]
  T N1, N2;          // yaw moment of the upper / lower rotor alone [N m]
};

// What an effect may read. In the balance setting the motion terms are zero
// and R_EB is the identity.
template <typename T>
struct EffectContext {
  const T* theta;                  // every parameter (BaseParameter indices first)
  Setting setting;
  T omega1, omega2;                // rotor speeds [rad/s]
  T delta_cx, delta_cy;            // swashplate angles as used (after any bias) [rad]
  T sigma;                         // interference loss (eq. 12)
  Vec3<T> T2_B;                    // lower-rotor force, eq. 9 with sigma on z (eq. 13)
  T rotor_z;                       // Z_T, the rotor z-force of eq. 13
  Vec3<T> v_B;                     // ground-relative velocity (u, v, w)
  Vec3<T> w_B;                     // body rates (p, q, r)
  T height;                        // h = -z [m] (flight only)
  // The effect's own states (kNumOwnStates of them) in flight; nullptr in the
  // balance setting and for effects without states.
  const T* own_states = nullptr;
};

struct EffectBase {
  // Measurement effects (gyro_bias, accel_bias) set this: the logged state
  // channels are then no longer the states themselves, and the estimators
  // take their outputs and Jacobians from the model for every channel.
  static constexpr bool kChangesFlightMeasurements = false;
  // Actuator effects: per input, the index in p of its lag time constant, or -1.
  static constexpr std::array<int, 4> kInputLag = {-1, -1, -1, -1};
  // States the effect owns (they join the state vector after the 12).
  static constexpr int kNumOwnStates = 0;
  // Their names, kNumOwnStates of them (reports: "<effect>.<name>").
  static std::vector<std::string> OwnStateNames() { return {}; }
  template <typename T>
  static void OwnStateDerivative(const T* /*p*/, const T* /*x*/, const T* /*s*/, T* /*sdot*/) {}
  template <typename T>
  static void AdjustInputs(const T* /*p*/, T* /*delta_cx*/, T* /*delta_cy*/) {}
  template <typename T>
  static void AddWindEarth(const T* /*p*/, Vec3<T>* /*wind_E*/) {}
  template <typename T>
  static void AddLoads(const EffectContext<T>& /*c*/, const T* /*p*/, AeroLoads<T>* /*loads*/) {}
  template <typename T>
  static void AddToFlightMeasurements(const T* /*p*/, T* /*y*/) {}
};

}  // namespace coaxid
