// The vehicle configuration (configs/glmav.yaml): known constants, nominal
// unknowns with bounds and scales, the interference-loss model and the enabled
// effects. Loaded into structs in one place, required fields checked
// (STYLE.md, item 8); the resolved configuration is written back next to every
// result so that a run can be repeated.
//
// File layout (YAML):
//   vehicle: glmav
//   known:   { m: {value: 0.25, unit: kg}, g: 9.81, ... }      # not estimated by default
//   unknown: { alpha: {value: -5.6e-5, lower: ..., upper: ..., scale: ...}, ... }
//   interference:
//     model: parametric            # or: table
//     table: {omega1: [..], omega2: [..], sigma: [[..], ..]}   # rows over omega1
//   effects:
//     gyroscopic: {J_r: {value: 1.0e-4}}   # enabled effects, parameter overrides
// A parameter entry is either a number (the value) or a map with value and
// optionally lower, upper, scale, estimated, unit.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/parameters.h"

namespace coaxid {

// A tabulated interference loss sigma(omega1, omega2) (model.md, decision 1;
// the paper's Fig. 9), bilinear between grid points, clamped outside.
struct SigmaTable {
  std::vector<double> omega1;  // rad/s, strictly increasing
  std::vector<double> omega2;  // rad/s, strictly increasing
  std::vector<double> sigma;   // row-major: sigma[i * omega2.size() + j] at (omega1[i], omega2[j])
  bool empty() const { return sigma.empty(); }
  // Throws InputError if sizes or ordering are wrong or a value is outside (0, 1].
  void Validate(const std::string& where) const;
};

enum class InterferenceModel { kParametric, kTable };

// Fields of one parameter entry that a file gave; unset ones keep defaults.
struct ParameterOverride {
  std::optional<double> value, lower, upper, scale;
  std::optional<bool> estimated;
  std::optional<std::string> unit;
  void ApplyTo(Parameter* p) const;
};

struct VehicleConfig {
  std::string vehicle = "glmav";
  std::string source;           // the file it came from
  ParameterSet parameters;      // the base parameters, in BaseParameter order
  InterferenceModel interference = InterferenceModel::kParametric;
  SigmaTable sigma_table;
  // Enabled effects (name -> overrides of its parameters), in file order.
  std::vector<std::pair<std::string, std::map<std::string, ParameterOverride>>> effects;
};

// Loads and checks a vehicle config. Throws InputError naming the file and the
// entry on a missing base parameter, an unknown key, a bad number or bounds.
VehicleConfig LoadVehicleConfig(const std::string& path);
// Same from YAML text; `source` names it in messages.
VehicleConfig ParseVehicleConfig(const std::string& yaml_text, const std::string& source);

// The resolved configuration as YAML text, from the full parameter set (base
// parameters plus effect parameters named "effect.param"): what a run really
// used. Loading it gives the same parameters and effects back.
std::string ResolvedConfigYaml(const VehicleConfig& config, const ParameterSet& all_parameters);

}  // namespace coaxid
