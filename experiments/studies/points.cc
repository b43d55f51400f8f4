#include "experiments/studies/points.h"

#include <algorithm>
#include <random>

#include "experiments/studies/random_draw.h"

namespace coaxid {

uint64_t MixSeed(uint64_t seed, uint64_t stream) {
  uint64_t z = seed + 0x9e3779b97f4a7c15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

namespace {

void ScaleAll(std::map<std::string, double>* table, double factor) {
  for (auto& [name, value] : *table) value *= factor;
}

void SetEffectStrength(const std::string& parameter, double value, Scenario* s) {
  const size_t dot = parameter.find('.');
  const std::string effect = parameter.substr(0, dot), name = parameter.substr(dot + 1);
  auto& effects = s->truth_effects;
  auto it = std::find_if(effects.begin(), effects.end(),
                         [&](const auto& e) { return e.first == effect; });
  if (value == 0) {
    if (it != effects.end()) effects.erase(it);
    return;
  }
  if (it == effects.end()) {
    effects.emplace_back(effect, std::map<std::string, ParameterOverride>{});
    it = effects.end() - 1;
  }
  it->second[name].value = value;
}

}  // namespace

std::vector<Scenario> PointScenarios(const StudySpec& spec, int point, uint64_t seed) {
  if (spec.randomise.enabled) return DrawRun(spec, seed).scenarios;
  std::vector<Scenario> out = spec.scenarios;
  const StudySweep& sweep = spec.sweep;
  for (size_t i = 0; i < out.size(); ++i) {
    Scenario& s = out[i];
    s.seed = MixSeed(seed, i);
    const bool flight = s.kind == Scenario::Kind::kFlight;
    switch (sweep.setting) {
      case SweepSetting::kNone:
      case SweepSetting::kInitialError:
        break;
      case SweepSetting::kNoiseScale:
        ScaleAll(&s.balance.noise_std, sweep.values[point]);
        ScaleAll(&s.flight.noise_std, sweep.values[point]);
        break;
      case SweepSetting::kExcitationScale:
        ScaleAll(&s.flight.excitation.amplitude, sweep.values[point]);
        for (double& d : s.balance.delta_cx) d *= sweep.values[point];
        for (double& d : s.balance.delta_cy) d *= sweep.values[point];
        break;
      case SweepSetting::kExcitationType:
        if (flight) {
          const std::string& t = sweep.types[point];
          s.flight.excitation.type = t == "multisine" ? Excitation::Type::kMultisine
                                     : t == "3211"    ? Excitation::Type::k3211
                                     : t == "doublet" ? Excitation::Type::kDoublet
                                                      : Excitation::Type::kNone;
        }
        break;
      case SweepSetting::kLogLength:
        if (flight) s.flight.duration_s = sweep.values[point];
        break;
      case SweepSetting::kSampleRate:
        s.flight.rate_hz = sweep.values[point];
        s.balance.rate_hz = sweep.values[point];
        break;
      case SweepSetting::kEffectStrength:
        SetEffectStrength(sweep.parameter, sweep.values[point], &s);
        break;
    }
  }
  return out;
}

Vehicle StartVehicle(const StudySpec& spec, int point, uint64_t seed) {
  Vehicle vehicle = MakeVehicle(spec.config);
  if (!spec.estimate.empty()) {
    for (const std::string& name : vehicle.parameters.FreeNames()) {
      if (std::find(spec.estimate.begin(), spec.estimate.end(), name) == spec.estimate.end()) {
        vehicle.parameters.SetEstimated(name, false);
      }
    }
  }
  if (spec.sweep.setting == SweepSetting::kInitialError) {
    const double e = spec.sweep.values[point];
    std::mt19937_64 rng(MixSeed(seed, 1000));
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int i : vehicle.parameters.FreeIndices()) {
      Parameter& p = vehicle.parameters.mutable_parameter(i);
      p.value = std::clamp(p.value * (1.0 + e * u(rng)), p.lower, p.upper);
    }
  }
  return vehicle;
}

}  // namespace coaxid
