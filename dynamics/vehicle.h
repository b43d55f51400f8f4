// A vehicle: the model structure (which effects, which sigma model) together
// with its full parameter set (base parameters, then each enabled effect's
// parameters as "effect.name"), built from a VehicleConfig in one place.
#pragma once

#include <string>

#include "core/parameters.h"
#include "core/vehicle_config.h"
#include "dynamics/vehicle_model.h"

namespace coaxid {

struct Vehicle {
  VehicleConfig config;
  ParameterSet parameters;
  VehicleModel model;

  // Names of the enabled effects, in parameter order.
  std::vector<std::string> EffectNames() const;
  // The resolved configuration (YAML) with the current parameter values.
  std::string ResolvedConfig() const { return ResolvedConfigYaml(config, parameters); }
};

// Builds the vehicle. Throws InputError on an unknown effect (listing the
// library), an unknown effect parameter, or an override outside bounds.
Vehicle MakeVehicle(const VehicleConfig& config);
Vehicle LoadVehicle(const std::string& config_path);

// The same vehicle with one more effect enabled (parameters at their
// defaults unless given), the other parameters kept at their current values.
Vehicle WithEffect(const Vehicle& vehicle, const std::string& effect,
                   const std::map<std::string, ParameterOverride>& overrides = {});
// The same vehicle without the effect (nothing changes if it has none).
Vehicle WithoutEffect(const Vehicle& vehicle, const std::string& effect);

}  // namespace coaxid
