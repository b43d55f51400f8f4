#include "experiments/simulation/excitation.h"

#include <algorithm>
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
  if (!spec.bands.empty()) {
    ShapeBands();
    return;
  }
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

namespace {

// Largest |sum of the sines| over one period, on a grid fine enough for the
// highest harmonic (at least 4000 points, 40 per cycle of the fastest).
double PeakOverPeriod(const std::vector<double>& frequency_hz, const std::vector<double>& amplitude,
                      const std::vector<double>& phase, double period_s) {
  double f_max = 0;
  for (double f : frequency_hz) f_max = std::max(f_max, f);
  const int n = std::max(4000, static_cast<int>(std::ceil(40 * f_max * period_s)));
  double peak = 0;
  for (int i = 0; i < n; ++i) {
    const double t = period_s * i / n;
    double s = 0;
    for (size_t j = 0; j < frequency_hz.size(); ++j) {
      s += amplitude[j] * std::sin(2 * M_PI * frequency_hz[j] * t + phase[j]);
    }
    peak = std::max(peak, std::fabs(s));
  }
  return peak;
}

}  // namespace

std::vector<std::array<std::vector<int>, 4>> BandHarmonics(const Excitation& spec) {
  const double df = 1.0 / spec.period_s;
  std::vector<std::array<std::vector<int>, 4>> out;
  int n = 0;          // harmonics dealt so far: the round-robin goes on across bands
  int last_dealt = 0;
  for (const Excitation::Band& band : spec.bands) {
    const int first = std::max(last_dealt + 1,
                               static_cast<int>(std::ceil(band.min_hz / df - 1e-9)));
    const int last = static_cast<int>(std::floor(band.max_hz / df + 1e-9));
    std::array<std::vector<int>, 4> harmonics;
    for (int k = first; k <= last; ++k, ++n) harmonics[n % 4].push_back(k);
    last_dealt = std::max(last_dealt, last);
    out.push_back(harmonics);
  }
  return out;
}

void ExcitationSignal::ShapeBands() {
  const double df = 1.0 / spec_.period_s;
  const std::vector<std::array<std::vector<int>, 4>> dealt = BandHarmonics(spec_);
  for (size_t b = 0; b < spec_.bands.size(); ++b) {
    const Excitation::Band& band = spec_.bands[b];
    const std::array<std::vector<int>, 4>& harmonics = dealt[b];
    for (int c = 0; c < 4; ++c) {
      auto it = band.rms.find(kChannels[c]);
      const double rms = it == band.rms.end() ? 0.0 : it->second;
      const int m = static_cast<int>(harmonics[c].size());
      if (rms == 0 || m == 0) continue;
      // m sines of equal amplitude A carry rms^2 = m A^2 / 2.
      const double a = rms * std::sqrt(2.0 / m);
      for (int k : harmonics[c]) sines_[c].push_back({k * df, 0.0, a});
    }
  }
  for (int c = 0; c < 4; ++c) {
    std::vector<Sine>& sines = sines_[c];
    std::sort(sines.begin(), sines.end(),
              [](const Sine& a, const Sine& b) { return a.frequency_hz < b.frequency_hz; });
    // Schroeder's phases for a given power spectrum p_j (shares of the
    // power): phi_j = -2 pi sum_{l<j} (j - l) p_l; for a flat spectrum this
    // is the -pi j (j + 1) / m of the single-band multisine.
    double power = 0;
    for (const Sine& w : sines) power += w.amplitude * w.amplitude;
    std::vector<double> f, a, phase;
    for (size_t j = 0; j < sines.size(); ++j) {
      double sum = 0;
      for (size_t l = 0; l < j; ++l) {
        sum += (j - l) * sines[l].amplitude * sines[l].amplitude / power;
      }
      sines[j].phase = -2 * M_PI * sum;
      f.push_back(sines[j].frequency_hz);
      a.push_back(sines[j].amplitude);
      phase.push_back(sines[j].phase);
    }
    amplitude_[c] = 1.0;
    peak_[c] = 1.0;
    band_peak_[c] = sines.empty() ? 0.0 : PeakOverPeriod(f, a, phase, spec_.period_s);
  }
}

double ExcitationSignal::Peak(int c) const {
  if (spec_.type == Excitation::Type::kNone) return 0;
  if (spec_.type == Excitation::Type::kMultisine && !spec_.bands.empty()) return band_peak_[c];
  return amplitude_[c];
}

InputVector ExcitationSignal::At(double t) const {
  InputVector out = Ungated(t);
  if (spec_.quiet.empty()) return out;
  // Off inside each quiet window, cosine fades over the ramp on either side.
  double gate = 1;
  const double ramp = Excitation::quiet_ramp_s;
  for (const auto& [from, to] : spec_.quiet) {
    if (t >= from && t <= to) return {0, 0, 0, 0};
    const double d = t < from ? from - t : t - to;
    if (d < ramp) gate *= 0.5 - 0.5 * std::cos(M_PI * d / ramp);
  }
  for (double& v : out) v *= gate;
  return out;
}

InputVector ExcitationSignal::Ungated(double t) const {
  InputVector out{0, 0, 0, 0};
  const double tau = t - spec_.start_s;
  if (spec_.type == Excitation::Type::kNone || tau < 0) return out;
  if (spec_.type == Excitation::Type::kMultisine) {
    for (int c = 0; c < 4; ++c) {
      double s = 0;
      for (const Sine& w : sines_[c]) {
        s += w.amplitude * std::sin(2 * M_PI * w.frequency_hz * tau + w.phase);
      }
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
