// What the vehicle applies during one hold interval [t0, t1) of a log: the
// logged row (held, model.md) and, for inputs that reach the vehicle through
// a first-order actuator lag (effects.md: servo_lag, motor_lag), where the
// lag starts.
// Inside the interval a lagged input is an exact exponential,
//   u(t) = c + (a0 - c) exp(-(t - t0) / T),                      (A)
// with c the logged value, a0 the applied value at t0 and T the time
// constant; from one row to the next (h = t1 - t0)
//   a1 = c + (a0 - c) E,  da1/dT = E da0/dT + (a0 - c) E h / T^2,  E = e^(-h/T).   (B)
// a0 depends on T through the whole log before t0; the recursion (B) carries
// that dependence as da0/dT, and (A) is evaluated with a0 + da0/dT (T - T0)
// so that a Jet T gets the exact first derivative (T0: the value a0 was
// computed at). The one formula the simulator, output-error, the EKF and the
// closing loop share.
#pragma once

#include <cmath>
#include <mutex>
#include <vector>

#include "core/input_hold.h"

namespace coaxid {

struct HeldInput {
  // Not an aggregate: a HeldInput brace-built from a row alone would start
  // its lagged inputs at 0. Build one with Steady or NextHeldInput.
  HeldInput() = default;

  InputVector logged{};       // the row's omega1, omega2 [rad/s], delta_cx, delta_cy [rad]
  double t0 = 0;              // start of the interval [s]
  InputVector start{};        // applied values at t0
  InputVector start_dlag{};   // d start / d (that input's time constant) [unit/s]
  InputVector lag{};          // the time constants start was computed with [s]; 0: no lag

  // An interval with no lag history: applied = logged (a log's first row, a
  // steady trim, a model without lag).
  static HeldInput Steady(const InputVector& u, double t0) {
    HeldInput h;
    h.logged = h.start = u;
    h.t0 = t0;
    return h;
  }
};

// (A) for input i at time t with time constant T (any scalar type).
template <typename T>
T LaggedInput(const HeldInput& held, int i, const T& time_constant, double t) {
  using std::exp;
  if (!(time_constant > T(0))) return T(held.logged[i]);
  const T start = held.start[i] + held.start_dlag[i] * (time_constant - held.lag[i]);
  return held.logged[i] + (start - held.logged[i]) * exp(-(t - held.t0) / time_constant);
}

// (B): the next interval's HeldInput, from this one's lag state and the next
// row (logged u at t1), with time constants lag (0 = no lag) per input.
HeldInput NextHeldInput(const HeldInput& held, const InputVector& lag, const InputVector& u,
                        double t1);

// Row 0 of a log as applied: the logged row when no input lags or the log
// starts with its first row; for a log cut from a longer one (a held-out
// tail), the lag walked through the source's rows before it
// (InputHold::lead_in): a rotor that lags its command by 0.19 s is not at
// its command when the tail starts (measured, CoaX flight: taken as
// settled, the EKF's held-out restart lost r within 0.25 s on every seed).
HeldInput FirstHeldInput(const InputHold& hold, const InputVector& lag);
// Row k of a log as applied, walking the lag from row 0 (O(k); O(1) when no
// input lags). lag: VehicleModel::InputLags.
HeldInput HeldInputAt(const InputHold& hold, int k, const InputVector& lag);
// Every row of a log as applied.
std::vector<HeldInput> HeldInputs(const InputHold& hold, const InputVector& lag);

// A log's rows as applied at the last lag asked for, shared by the segments
// of a multiple-shooting fit: each asks for its first row, and the log is
// walked once per lag instead of once per segment (a 20-minute log has 1200
// segments). Thread-safe (Ceres evaluates segments in parallel); without a
// lag it stores nothing.
class HeldInputPath {
 public:
  explicit HeldInputPath(const InputHold& hold) : hold_(hold) {}  // hold must outlive it
  HeldInput At(int k, const InputVector& lag) const;

 private:
  const InputHold& hold_;
  mutable std::mutex mutex_;
  mutable InputVector lag_{-1, -1, -1, -1};
  mutable std::vector<HeldInput> path_;
};

}  // namespace coaxid
