// Identification excitation added to the controller's outputs: a multisine
// (orthogonal across channels, Schroeder phases, so the four inputs are
// uncorrelated over a period), or 3211 or doublet pulse trains (channels take
// turns).
#pragma once

#include <array>
#include <vector>

#include "core/input_hold.h"
#include "experiments/simulation/scenario.h"

namespace coaxid {

class ExcitationSignal {
 public:
  explicit ExcitationSignal(const Excitation& spec);
  // Perturbation of (omega1, omega2, delta_cx, delta_cy) at time t [s].
  InputVector At(double t) const;

 private:
  struct Sine {
    double frequency_hz, phase;
  };
  Excitation spec_;
  std::array<double, 4> amplitude_{};
  std::array<std::vector<Sine>, 4> sines_;
  std::array<double, 4> peak_{};  // peak of the unit-amplitude sum, to normalise
};

}  // namespace coaxid
