// State, input and frame notation (model.md, "Frames and state"; STYLE.md,
// item 4). Body frame B: origin at G, x forward, y right, z down the rotor
// shaft. Earth frame E: North-East-Down. R_EB rotates body to earth (eq. 1).
// v_B is a velocity in body axes, w_B the body rates (p, q, r).
#pragma once

#include <Eigen/Core>

namespace coaxid {

// The 12 states of eqs. 34-49, in this order everywhere (vectors, CSV, EKF).
enum StateIndex : int {
  kX, kY, kZ,           // position of G, earth (NED) axes [m]; height h = -z
  kU, kV, kW,           // velocity of G, body axes [m/s]
  kPhi, kTheta, kPsi,   // Euler angles ZYX [rad]
  kP, kQ, kR,           // body rates [rad/s]
  kNumStates
};
// The flight channels (dynamics/outputs.h): the 12 states in StateIndex
// order, then the accelerometer's specific force ax, ay, az.
inline constexpr int kNumFlightChannels = kNumStates + 3;
enum FlightChannel : int { kAx = kNumStates, kAy, kAz };
// The Euler angles, whose differences are taken on the circle.
inline bool IsEulerAngle(int state_or_channel) {
  return state_or_channel == kPhi || state_or_channel == kTheta || state_or_channel == kPsi;
}
// "x", "y", ..., "r": the log-format column names of the states.
const char* StateName(int index);

// The 4 inputs, zero-order hold (model.md): upper / lower rotor speed [rad/s],
// swashplate incidence angles [rad]. Same order as core/input_hold.h.
enum InputIndex : int { kOmega1, kOmega2, kDeltaCx, kDeltaCy, kNumInputs };

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Mat3 = Eigen::Matrix<T, 3, 3>;
template <typename T>
using StateVector = Eigen::Matrix<T, kNumStates, 1>;

using State = StateVector<double>;

}  // namespace coaxid
