#include "dynamics/vehicle.h"

#include <algorithm>

#include "core/errors.h"

namespace coaxid {

std::vector<std::string> Vehicle::EffectNames() const {
  std::vector<std::string> names;
  for (const auto& [name, overrides] : config.effects) names.push_back(name);
  return names;
}

Vehicle MakeVehicle(const VehicleConfig& config) {
  Vehicle vehicle;
  vehicle.config = config;
  vehicle.parameters = config.parameters;
  std::array<int, kNumEffects> offsets;
  offsets.fill(-1);
  for (const auto& [name, overrides] : config.effects) {
    const int index = EffectIndex(name);
    if (index < 0) {
      std::string known;
      for (const auto& info : EffectLibrary()) known += (known.empty() ? "" : ", ") + info.name;
      throw InputError(config.source + ": effects: unknown effect '" + name +
                       "' (the library has: " + known + ")");
    }
    if (offsets[index] >= 0) {
      throw InputError(config.source + ": effects: '" + name + "' enabled twice");
    }
    const EffectInfo& info = EffectLibrary()[index];
    for (const auto& [pname, o] : overrides) {
      bool found = false;
      for (const auto& spec : info.parameters) found = found || spec.name == pname;
      if (!found) {
        std::string known;
        for (const auto& spec : info.parameters) known += (known.empty() ? "" : ", ") + spec.name;
        throw InputError(config.source + ": effects." + name + ": unknown parameter '" + pname +
                         "' (expected: " + known + ")");
      }
    }
    offsets[index] = vehicle.parameters.size();
    for (const auto& spec : info.parameters) {
      Parameter p;
      p.name = name + "." + spec.name;
      p.value = spec.value;
      p.lower = spec.lower;
      p.upper = spec.upper;
      p.scale = spec.scale;
      p.estimated = true;
      p.unit = spec.unit;
      auto it = overrides.find(spec.name);
      if (it != overrides.end()) it->second.ApplyTo(&p);
      try {
        vehicle.parameters.Add(p);
      } catch (const InputError& e) {
        throw InputError(config.source + ": effects." + name + ": " + e.what());
      }
    }
  }
  auto table = std::make_shared<const SigmaTable>(config.sigma_table);
  vehicle.model = VehicleModel(config.interference, table, offsets);
  return vehicle;
}

Vehicle LoadVehicle(const std::string& config_path) {
  return MakeVehicle(LoadVehicleConfig(config_path));
}

namespace {

// The vehicle's config with every parameter at its current value (effect
// parameters as overrides of their effects), to be rebuilt by MakeVehicle.
VehicleConfig ConfigAtCurrentValues(const Vehicle& vehicle) {
  VehicleConfig config = vehicle.config;
  // Drop effect parameters from the base set; MakeVehicle re-adds them.
  ParameterSet base;
  for (int i = 0; i < kNumBaseParameters; ++i) base.Add(vehicle.parameters[i]);
  config.parameters = base;
  for (auto& [name, o] : config.effects) {
    for (const auto& spec : EffectLibrary()[EffectIndex(name)].parameters) {
      const Parameter& current = vehicle.parameters.Get(name + "." + spec.name);
      ParameterOverride keep;
      keep.value = current.value;
      keep.lower = current.lower;
      keep.upper = current.upper;
      keep.scale = current.scale;
      keep.estimated = current.estimated;
      o[spec.name] = keep;
    }
  }
  return config;
}

}  // namespace

Vehicle WithEffect(const Vehicle& vehicle, const std::string& effect,
                   const std::map<std::string, ParameterOverride>& overrides) {
  VehicleConfig config = ConfigAtCurrentValues(vehicle);
  config.effects.emplace_back(effect, overrides);
  return MakeVehicle(config);
}

Vehicle WithoutEffect(const Vehicle& vehicle, const std::string& effect) {
  VehicleConfig config = ConfigAtCurrentValues(vehicle);
  auto& effects = config.effects;
  effects.erase(std::remove_if(effects.begin(), effects.end(),
                               [&](const auto& e) { return e.first == effect; }),
                effects.end());
  return MakeVehicle(config);
}

}  // namespace coaxid
