// The output (measurement) models: what each log column is as a function of
// the state, the inputs and the parameters. Written once, templated, and
// shared by every estimator (output-error, EKF, the closing loop).
//  - flight (log-format.md): the 12 states themselves and the accelerometer
//    (model.md, decision 7: specific force (T + f_body + effects) / m);
//  - balance (decision 5): the aerodynamic loads X..N and the per-rotor
//    Z1, Z2, N1, N2.
#pragma once

#include "dynamics/vehicle_model.h"

namespace coaxid {

// Flight channels (kNumFlightChannels, FlightChannel): dynamics/state.h.
// Balance channels.
enum BalanceChannel : int { kBalanceX, kBalanceY, kBalanceZ, kBalanceL, kBalanceM, kBalanceN,
                            kBalanceZ1, kBalanceZ2, kBalanceN1, kBalanceN2, kNumBalanceChannels };

// Log-format column names.
const char* FlightChannelName(int channel);
const char* BalanceChannelName(int channel);
// -1 if `column` is not a channel of that kind.
int FlightChannelIndex(const std::string& column);
int BalanceChannelIndex(const std::string& column);

// All 15 flight outputs at state x with inputs u: what the sensors read,
// after any measurement effect (gyro_bias, accel_bias).
template <typename T>
void FlightOutputs(const VehicleModel& model, const T* theta, const T* x, const T* u, T* y) {
  for (int i = 0; i < kNumStates; ++i) y[i] = x[i];
  const Vec3<T> f = model.SpecificForce(theta, x, u);
  y[kAx] = f[0];
  y[kAy] = f[1];
  y[kAz] = f[2];
  model.AddToFlightMeasurements(theta, y);
}

// FlightOutputs at the start of the hold interval `held` (its row's time),
// with the inputs the vehicle applied then.
template <typename T>
void FlightOutputsAt(const VehicleModel& model, const T* theta, const T* x, const HeldInput& held,
                     T* y) {
  T u[kNumInputs];
  model.AppliedInput(theta, held, held.t0, u);
  FlightOutputs(model, theta, x, u, y);
}

// All 10 balance outputs with inputs u (eqs. 57-63 with model.md's decisions).
template <typename T>
void BalanceOutputs(const VehicleModel& model, const T* theta, const T* u, T* y) {
  const AeroLoads<T> a = model.Loads(theta, u, Setting::kBalance, static_cast<const T*>(nullptr));
  for (int i = 0; i < 3; ++i) y[kBalanceX + i] = a.force_B[i];
  for (int i = 0; i < 3; ++i) y[kBalanceL + i] = a.moment_B[i];
  y[kBalanceZ1] = a.Z1;
  y[kBalanceZ2] = a.Z2;
  y[kBalanceN1] = a.N1;
  y[kBalanceN2] = a.N2;
}

}  // namespace coaxid
