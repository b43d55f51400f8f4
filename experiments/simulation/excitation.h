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

// The harmonics k (frequency k / period_s) each input gets in each band of
// a band-shaped multisine: [band][input]. Each band's harmonics, from its
// lowest to its highest frequency (a harmonic on the boundary of two bands
// belongs to the lower), are dealt round-robin to the four inputs, the
// dealing going on from band to band, so no two inputs share a frequency.
std::vector<std::array<std::vector<int>, 4>> BandHarmonics(const Excitation& spec);

class ExcitationSignal {
 public:
  explicit ExcitationSignal(const Excitation& spec);
  // Perturbation of (omega1, omega2, delta_cx, delta_cy) at time t [s];
  // zero inside the spec's quiet windows.
  InputVector At(double t) const;
  // Peak |perturbation| of channel c over one period (multisine), or its
  // pulse level (3211, doublet).
  double Peak(int c) const;

 private:
  struct Sine {
    double frequency_hz, phase;
    double amplitude = 1;  // before the channel's normalisation (peak_)
  };
  void ShapeBands();  // sines_ and peak_ of a multisine given by bands
  InputVector Ungated(double t) const;  // At() before the quiet windows
  Excitation spec_;
  std::array<double, 4> amplitude_{};
  std::array<std::vector<Sine>, 4> sines_;
  std::array<double, 4> peak_{};  // peak of the unit-amplitude sum, to normalise
  std::array<double, 4> band_peak_{};  // by bands: the peak of the shaped sum
};

}  // namespace coaxid
