#include "experiments/simulation/excitation.h"

#include <cmath>

namespace coaxid {
namespace {
constexpr const char* kChannels[4] = {"omega1", "omega2", "delta_cx", "delta_cy"};
}

ExcitationSignal::ExcitationSignal(const Excitation& spec) : spec_(spec) {
  for (int c = 0; c < 4; ++c) {
    auto it = spec.amplitude.find(kChannels[c]);
    amplitude_[c] = it == spec.amplitude.end() ? 0.0 : it->second;
  }
  if (spec.type != Excitation::Type::kMultisine) return;
  // Harmonics of 1/period inside the band, dealt round-robin to the channels
  // so no two channels share a frequency (orthogonal multisines).
  const double df = 1.0 / spec.period_s;
  const int first = std::max(1, static_cast<int>(std::ceil(spec.min_hz / df)));
  const int last = static_cast<int>(std::floor(spec.max_hz / df));
  for (int k = first, n = 0; k <= last; ++k, ++n) sines_[n % 4].push_back({k * df, 0.0});
  for (int c = 0; c < 4; ++c) {
    const int m = static_cast<int>(sines_[c].size());
    // Schroeder phases keep the crest factor low.
    for (int j = 0; j < m; ++j) sines_[c][j].phase = -M_PI * j * (j + 1) / std::max(m, 1);
    double peak = 0;
    for (int i = 0; i < 4000; ++i) {
      const double t = spec.period_s * i / 4000.0;
      double s = 0;
      for (const Sine& w : sines_[c]) s += std::sin(2 * M_PI * w.frequency_hz * t + w.phase);
      peak = std::max(peak, std::fabs(s));
    }
    peak_[c] = peak > 0 ? peak : 1.0;
  }
}

InputVector ExcitationSignal::At(double t) const {
  InputVector out{0, 0, 0, 0};
  const double tau = t - spec_.start_s;
  if (spec_.type == Excitation::Type::kNone || tau < 0) return out;
  if (spec_.type == Excitation::Type::kMultisine) {
    for (int c = 0; c < 4; ++c) {
      double s = 0;
      for (const Sine& w : sines_[c]) s += std::sin(2 * M_PI * w.frequency_hz * tau + w.phase);
      out[c] = amplitude_[c] * s / peak_[c];
    }
    return out;
  }
  // Pulse trains; channels take turns, one slot each, repeating.
  //   3211:    +1 for 3 units, -1 for 2, +1 for 1, -1 for 1, then 3 units of rest;
  //   doublet: +1 for 2 units, -1 for 2, then 4 units of rest.
  struct Pulse {
    double until_units, level;
  };
  static const std::vector<Pulse> k3211Pulses = {{3, 1}, {5, -1}, {6, 1}, {7, -1}};
  static const std::vector<Pulse> kDoubletPulses = {{2, 1}, {4, -1}};
  const bool doublet = spec_.type == Excitation::Type::kDoublet;
  const std::vector<Pulse>& pulses = doublet ? kDoubletPulses : k3211Pulses;
  const double unit = spec_.pulse_s;
  const double slot = (doublet ? 8 : 10) * unit;
  const int channel = static_cast<int>(std::floor(tau / slot)) % 4;
  const double u = std::fmod(tau, slot) / unit;
  double level = 0;
  for (const Pulse& pulse : pulses) {
    if (u < pulse.until_units) {
      level = pulse.level;
      break;
    }
  }
  out[channel] = amplitude_[channel] * level;
  return out;
}

}  // namespace coaxid
