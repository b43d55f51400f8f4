// Zero-order hold of logged inputs (model.md: the value in row k holds on
// [t_k, t_{k+1})). The one piece every consumer (simulator, EKF, output-error)
// uses to ask "what was the input at time t" and "where does it change".
#pragma once

#include <array>
#include <vector>

#include "core/log.h"

namespace coaxid {

// omega1 [rad/s], omega2 [rad/s], delta_cx [rad], delta_cy [rad].
using InputVector = std::array<double, 4>;

class InputHold {
 public:
  InputHold() = default;
  // times strictly increasing, inputs.size() == times.size(). Throws InputError otherwise.
  InputHold(std::vector<double> times, std::vector<InputVector> inputs);
  // From a log's t, omega1, omega2, delta_cx, delta_cy columns.
  static InputHold FromLog(const Log& log);

  int size() const { return static_cast<int>(times_.size()); }
  double time(int k) const { return times_[k]; }
  const InputVector& input(int k) const { return inputs_[k]; }
  const std::vector<double>& times() const { return times_; }

  // Index k of the hold interval containing t: times[k] <= t < times[k+1]
  // (the last sample holds for ever; t before the first sample gives 0).
  // O(log n).
  int IntervalAt(double t) const;
  // The held input at time t.
  const InputVector& At(double t) const { return inputs_[IntervalAt(t)]; }

  // A hold cut from a longer log (a held-out tail): the source's rows just
  // before the first one (times strictly before time(0), increasing). They
  // only say where a lagged input stands at the first row
  // (dynamics/held_input.h: FirstHeldInput); every other use of the hold
  // ignores them. Throws InputError if they are not before time(0).
  void SetLeadIn(std::vector<double> times, std::vector<InputVector> inputs);
  const std::vector<double>& lead_in_times() const { return lead_in_times_; }
  const std::vector<InputVector>& lead_in_inputs() const { return lead_in_inputs_; }

 private:
  std::vector<double> times_;
  std::vector<InputVector> inputs_;
  std::vector<double> lead_in_times_;
  std::vector<InputVector> lead_in_inputs_;
};

}  // namespace coaxid
