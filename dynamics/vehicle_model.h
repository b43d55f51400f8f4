// The GLMAV model of the paper (eqs. 6-49) with model.md's decisions and any
// enabled effects of the library, written once and templated on the scalar
// type: the simulator runs it with double, the EKF's Jacobians and Ceres with
// ceres::Jet (STYLE.md, item 1). The model holds structure only (which
// effects, which sigma model); every number comes in through theta, the
// full parameter vector of a ParameterSet (STYLE.md, item 2).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "core/parameters.h"
#include "core/vehicle_config.h"
#include "dynamics/effects/effect_library.h"
#include "dynamics/held_input.h"
#include "dynamics/interference_loss.h"
#include "dynamics/rigid_body.h"
#include "dynamics/state.h"
#include "dynamics/truth_only_loads.h"

namespace coaxid {

// Smoothing scales for the two kinks of the model (STYLE.md, item 7): the
// wake-speed radicand of eq. 46 (m^2/s^2) and the airspeed norm of eq. 25
// (m/s). At hover the radicand is ~45 m^2/s^2, so the change is ~1e-14.
inline constexpr double kWakeRadicandSmoothing = 1e-6;
inline constexpr double kAirspeedSmoothing = 1e-6;

class VehicleModel {
 public:
  // The paper's model: parametric sigma, no effect.
  VehicleModel() {
    effect_offset_.fill(-1);
    state_offset_.fill(-1);
    lag_index_.fill(-1);
  }
  // effect_offset[i]: index in theta of library effect i's first parameter,
  // or -1 if the effect is off. A table model needs a table.
  VehicleModel(InterferenceModel interference, std::shared_ptr<const SigmaTable> table,
               const std::array<int, kNumEffects>& effect_offset);

  // The state vector: the 12 rigid-body states (StateIndex), then the states
  // of enabled effects that own some (stabilizer_bar), in library order.
  int NumStates() const { return kNumStates + num_effect_states_; }
  bool HasEffectStates() const { return num_effect_states_ > 0; }
  // x (at least the 12 rigid-body states) as this model's state vector: the
  // effect states x does not hold set to `effect_state` (0: at rest; a small
  // value where their parameters must show, as in sensitivity checks).
  Eigen::VectorXd StateOf(const Eigen::VectorXd& x, double effect_state = 0.0) const {
    Eigen::VectorXd out = Eigen::VectorXd::Constant(NumStates(), effect_state);
    const int given = std::min<int>(static_cast<int>(x.size()), NumStates());
    out.head(given) = x.head(given);
    return out;
  }
  // Index in the state vector of library effect i's first own state, or -1.
  int EffectStateOffset(int library_index) const { return state_offset_[library_index]; }
  // The name of state `index`: "x" ... "r" (StateName), then "<effect>.<state>"
  // ("stabilizer_bar.b_x").
  std::string NameOfState(int index) const;
  std::vector<std::string> StateNames() const {
    std::vector<std::string> names;
    for (int i = 0; i < NumStates(); ++i) names.push_back(NameOfState(i));
    return names;
  }

  bool EffectEnabled(int library_index) const { return effect_offset_[library_index] >= 0; }
  int EffectOffset(int library_index) const { return effect_offset_[library_index]; }
  InterferenceModel interference() const { return interference_; }
  // Whether an enabled effect changes what the flight sensors read
  // (EffectBase::kChangesFlightMeasurements): then the logged state channels
  // are not the states themselves.
  bool ChangesFlightMeasurements() const { return changes_measurements_; }
  // Whether an enabled actuator effect (servo_lag) lags an input: then what
  // the vehicle applies in flight is not the logged row (dynamics/held_input.h).
  bool LagsInputs() const { return lags_inputs_; }
  // The lag time constants in theta per input (0 where none) [s].
  InputVector InputLags(const double* theta) const {
    InputVector lag{0, 0, 0, 0};
    for (int i = 0; i < kNumInputs; ++i) {
      if (lag_index_[i] >= 0) lag[i] = theta[lag_index_[i]];
    }
    return lag;
  }
  // The inputs applied at time t of the interval `held` (flight; eq. (A) of
  // dynamics/held_input.h for lagged inputs, the logged row otherwise).
  template <typename T>
  void AppliedInput(const T* theta, const HeldInput& held, double t, T* u) const {
    for (int i = 0; i < kNumInputs; ++i) {
      u[i] = lag_index_[i] >= 0 ? LaggedInput(held, i, theta[lag_index_[i]], t)
                                : T(held.logged[i]);
    }
  }

  // Simulated truths only (dynamics/truth_only_loads.h): loads outside the
  // library, applied by the double-valued model alone.
  void SetTruthOnlyLoads(std::shared_ptr<const TruthOnlyLoads> loads) {
    truth_only_ = std::move(loads);
  }
  bool HasTruthOnlyLoads() const { return truth_only_ != nullptr; }

  // Aerodynamic loads in body axes, gravity excluded (eqs. 6-33; in the
  // balance setting eqs. 57-63 with model.md decision 5). x is the state
  // vector (NumStates() entries) in flight and ignored (nullptr allowed) in
  // the balance setting, where u = v = w = 0, no rotation and level attitude.
  template <typename T>
  AeroLoads<T> Loads(const T* theta, const T* input, Setting setting, const T* x) const;

  // The state derivative: eqs. 34-49 for the 12 rigid-body states, then
  // each enabled effect's own states.
  template <typename T>
  void Derivative(const T* theta, const T* x, const T* input, T* xdot) const;

  // Accelerometer output (model.md, decision 7): specific force in body axes,
  // (T + f_body + effect forces) / m, gravity excluded [m/s^2].
  template <typename T>
  Vec3<T> SpecificForce(const T* theta, const T* x, const T* input) const {
    return Loads(theta, input, Setting::kFlight, x).force_B / theta[kMass];
  }

  // The measurement effects (effects.md, measurement and actuator
  // candidates): y, the 15 flight channels' true values, becomes what the
  // sensors log.
  template <typename T>
  void AddToFlightMeasurements(const T* theta, T* y) const {
    if (!changes_measurements_) return;
    ForEachEnabledEffect(theta, [&](auto effect, const T* p) {
      decltype(effect)::AddToFlightMeasurements(p, y);
    });
  }

 private:
  // Loads() with the body-to-earth rotation already known (flight).
  template <typename T>
  AeroLoads<T> LoadsGivenRotation(const T* theta, const T* input, Setting setting, const T* x,
                                  const Mat3<T>& R_EB) const;

  // Calls f(Effect{}, effect parameters) for each enabled effect.
  template <typename T, typename F>
  void ForEachEnabledEffect(const T* theta, F&& f) const {
    ForEachEffectType([&](auto effect, int i) {
      if (effect_offset_[i] >= 0) f(effect, theta + effect_offset_[i]);
    });
  }

  InterferenceModel interference_ = InterferenceModel::kParametric;
  std::shared_ptr<const SigmaTable> table_;
  std::array<int, kNumEffects> effect_offset_;
  std::array<int, kNumEffects> state_offset_;  // x index of each effect's own states, or -1
  int num_effect_states_ = 0;
  std::array<int, kNumInputs> lag_index_;  // theta index of each input's lag, or -1
  bool any_effect_ = false;
  bool lags_inputs_ = false;
  bool changes_measurements_ = false;
  std::shared_ptr<const TruthOnlyLoads> truth_only_;
};

template <typename T>
AeroLoads<T> VehicleModel::Loads(const T* theta, const T* input, Setting setting,
                                 const T* x) const {
  const Mat3<T> R_EB = setting == Setting::kFlight
                           ? BodyToEarth(x[kPhi], x[kTheta], x[kPsi])
                           : Mat3<T>(Mat3<T>::Identity());
  return LoadsGivenRotation(theta, input, setting, x, R_EB);
}

template <typename T>
AeroLoads<T> VehicleModel::LoadsGivenRotation(const T* theta, const T* input, Setting setting,
                                              const T* x, const Mat3<T>& R_EB) const {
  using std::sqrt;
  const T& alpha = theta[kAlpha];
  const T& beta = theta[kBeta];
  const T& rho = theta[kAirDensity];
  const T w1 = input[kOmega1] * input[kOmega1];
  const T w2 = input[kOmega2] * input[kOmega2];
  T delta_cx = input[kDeltaCx];
  T delta_cy = input[kDeltaCy];
  if (any_effect_) {
    ForEachEnabledEffect(theta, [&](auto effect, const T* p) {
      decltype(effect)::AdjustInputs(p, &delta_cx, &delta_cy);
    });
  }
  T sx, cx, sy, cy;
  SinCos(delta_cx, &sx, &cx);
  SinCos(delta_cy, &sy, &cy);

  // Interference loss (eq. 12; model.md, decision 1).
  const T sigma = interference_ == InterferenceModel::kTable
                      ? InterferenceLossFromTable(*table_, input[kOmega1], input[kOmega2])
                      : InterferenceLoss(theta[kSigma0], input[kOmega1], input[kOmega2]);

  AeroLoads<T> loads;
  // Rotor forces, eqs. 6, 9, 12-13: sigma on the z-components only.
  loads.Z1 = sigma * alpha * w1;
  loads.Z2 = sigma * beta * cx * cy * w2;
  const Vec3<T> T2_B(-beta * sy * cx * w2, -beta * sx * w2, loads.Z2);
  const T rotor_z = loads.Z1 + loads.Z2;  // [T]_zb, eq. 12

  // Airflow, eqs. 43-46 (eqs. 21-23): V_tot = V_prop - V_body + V_wind.
  // Eq. 46 with model.md decision 3: V_prop = sqrt(max(radicand, 0)), smoothed.
  const T radicand = T(-2) * rotor_z / (rho * T(M_PI) * theta[kRotorRadius] * theta[kRotorRadius]);
  // radicand + root, written for a negative radicand as eps^2 / (root -
  // radicand) (the same number): the sum cancels to exactly 0 once
  // radicand < ~-70, and the outer sqrt's derivative at 0 is infinite (a
  // rotor pushing down made the Jacobian NaN: study run p0_s33,
  // docs/discover_confusion.md).
  const T eps2 = T(kWakeRadicandSmoothing * kWakeRadicandSmoothing);
  const T root = sqrt(radicand * radicand + eps2);
  const T positive_part = radicand >= T(0) ? radicand + root : eps2 / (root - radicand);
  const T v_prop = sqrt(T(0.5) * positive_part);
  const bool flight = setting == Setting::kFlight;
  Vec3<T> v_B = Vec3<T>::Zero(), w_B = Vec3<T>::Zero();
  T height(1e6);  // a balance is far from the floor (sect. 3)
  if (flight) {
    v_B << x[kU], x[kV], x[kW];
    w_B << x[kP], x[kQ], x[kR];
    height = -x[kZ];
  }
  Vec3<T> wind_E = Vec3<T>::Zero();
  if (any_effect_) {
    ForEachEnabledEffect(theta, [&](auto effect, const T* p) {
      decltype(effect)::AddWindEarth(p, &wind_E);
    });
  }
  const Vec3<T> wind_B = R_EB.transpose() * wind_E;  // earth -> body
  const T V_ux = -v_B[0] + wind_B[0];           // eq. 43
  const T V_vy = -v_B[1] + wind_B[1];           // eq. 44
  const T V_wz = v_prop - v_B[2] + wind_B[2];   // eq. 45
  const T V_tot = sqrt(V_ux * V_ux + V_vy * V_vy + V_wz * V_wz +
                       T(kAirspeedSmoothing * kAirspeedSmoothing));  // eq. 25

  // Body force, eq. 24 with plus signs on all axes (model.md, decision 2).
  const T half_rho = T(0.5) * rho;
  const T S_c = T(2) * theta[kBodyRadius] * theta[kBodyLength];                 // eq. 26
  const T S_s = T(M_PI) * theta[kBodyRadius] * theta[kBodyRadius];            // eq. 26
  loads.force_B << T2_B[0] + half_rho * S_c * theta[kCx] * V_ux * V_tot,       // eq. 13 + 24
      T2_B[1] + half_rho * S_c * theta[kCy] * V_vy * V_tot,                    //
      rotor_z + half_rho * S_s * theta[kCz] * V_wz * V_tot;                    //

  // Moments, eqs. 31-33 (model.md, decision 4); the body force makes none.
  const T& d = theta[kHubDistance];
  loads.N1 = theta[kGamma1] * w1;
  loads.N2 = theta[kGamma2] * w2;
  loads.moment_B << -d * beta * sx * w2,  // eq. 31
      d * beta * sy * cx * w2,            // eq. 32
      loads.N1 + loads.N2;                // eq. 33

  bool truth_only = false;
  if constexpr (std::is_same_v<T, double>) truth_only = truth_only_ != nullptr;
  if (any_effect_ || truth_only) {
    EffectContext<T> context{theta, setting, input[kOmega1], input[kOmega2], delta_cx,
                             delta_cy, sigma, T2_B, rotor_z, v_B, w_B, height};
    ForEachEffectType([&](auto effect, int i) {
      using Effect = decltype(effect);
      if (effect_offset_[i] < 0) return;
      if constexpr (Effect::kNumOwnStates > 0) {
        context.own_states = flight ? x + state_offset_[i] : nullptr;
      }
      Effect::AddLoads(context, theta + effect_offset_[i], &loads);
      context.own_states = nullptr;
    });
    if constexpr (std::is_same_v<T, double>) {
      if (truth_only) truth_only_->Add(context, &loads);
    }
  }
  return loads;
}

template <typename T>
void VehicleModel::Derivative(const T* theta, const T* x, const T* input, T* xdot) const {
  const EulerSines<T> e = EulerSinesOf(x[kPhi], x[kTheta], x[kPsi]);
  const Mat3<T> R_EB = BodyToEarth(e);
  const AeroLoads<T> loads = LoadsGivenRotation(theta, input, Setting::kFlight, x, R_EB);
  // Weight in body axes, eq. 27: R_EB^T (0, 0, m g); total force eq. 28.
  const T mg = theta[kMass] * theta[kGravity];
  const Vec3<T> F_B = loads.force_B + mg * Vec3<T>(R_EB(2, 0), R_EB(2, 1), R_EB(2, 2));
  RigidBodyDerivative(x, e, R_EB, F_B, loads.moment_B, theta[kMass], theta[kIxx], theta[kIyy],
                      theta[kIzz], xdot);
  if (num_effect_states_ == 0) return;
  ForEachEffectType([&](auto effect, int i) {
    using Effect = decltype(effect);
    if constexpr (Effect::kNumOwnStates > 0) {
      if (effect_offset_[i] < 0) return;
      Effect::OwnStateDerivative(theta + effect_offset_[i], x, x + state_offset_[i],
                                 xdot + state_offset_[i]);
    }
  });
}

}  // namespace coaxid
