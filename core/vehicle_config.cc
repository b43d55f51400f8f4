#include "core/vehicle_config.h"

#include <cmath>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/yaml_util.h"

namespace coaxid {

void ParameterOverride::ApplyTo(Parameter* p) const {
  if (value) p->value = *value;
  if (lower) p->lower = *lower;
  if (upper) p->upper = *upper;
  if (scale) p->scale = *scale;
  if (estimated) p->estimated = *estimated;
  if (unit) p->unit = *unit;
}

void SigmaTable::Validate(const std::string& where) const {
  const size_t n1 = omega1.size(), n2 = omega2.size();
  if (n1 < 2 || n2 < 2) throw InputError(where + ": the sigma table needs at least 2x2 points");
  if (sigma.size() != n1 * n2) {
    throw InputError(where + ": sigma has " + std::to_string(sigma.size()) + " values, expected " +
                     std::to_string(n1) + " x " + std::to_string(n2));
  }
  for (size_t i = 1; i < n1; ++i) {
    if (!(omega1[i] > omega1[i - 1])) throw InputError(where + ": omega1 not increasing");
  }
  for (size_t j = 1; j < n2; ++j) {
    if (!(omega2[j] > omega2[j - 1])) throw InputError(where + ": omega2 not increasing");
  }
  for (double s : sigma) {
    if (!(s > 0 && s <= 1)) throw InputError(where + ": sigma values must lie in (0, 1]");
  }
}

namespace {

// Defaults for bounds and scales when the file gives only a value: bounds keep
// each unknown's physical sign (model.md), the scale is the magnitude.
Parameter DefaultParameter(int index) {
  Parameter p;
  p.name = BaseParameterName(index);
  p.estimated = index >= kAlpha;
  return p;
}

}  // namespace

VehicleConfig ParseVehicleConfig(const std::string& yaml_text, const std::string& source) {
  const YAML::Node root = ParseYaml(yaml_text, source);
  if (!root.IsMap()) throw InputError(source + ": expected a YAML map at the top level");
  CheckKeys(root, {"vehicle", "known", "unknown", "interference", "effects"}, source);
  VehicleConfig config;
  config.source = source;
  if (root["vehicle"]) config.vehicle = ReadString(root["vehicle"], source + ": vehicle");

  for (const char* section : {"known", "unknown"}) {
    if (!root[section] || !root[section].IsMap()) {
      throw InputError(source + ": missing section '" + section + "'");
    }
  }
  std::vector<std::string> known_names, unknown_names;
  for (int i = 0; i < kNumBaseParameters; ++i) {
    (i < kAlpha ? known_names : unknown_names).push_back(BaseParameterName(i));
  }
  CheckKeys(root["known"], known_names, source + ": known");
  CheckKeys(root["unknown"], unknown_names, source + ": unknown");
  for (int i = 0; i < kNumBaseParameters; ++i) {
    const char* section = i < kAlpha ? "known" : "unknown";
    const std::string name = BaseParameterName(i);
    const YAML::Node entry = root[section][name];
    const std::string where = source + ": " + section + "." + name;
    if (!entry) throw InputError(where + ": missing (every model.md parameter is required)");
    Parameter p = DefaultParameter(i);
    const ParameterOverride o = ReadParameterOverride(entry, where);
    if (!o.value) throw InputError(where + ": no value");
    o.ApplyTo(&p);
    if (!o.scale) p.scale = std::fabs(p.value) > 0 ? std::fabs(p.value) : 1.0;
    try {
      config.parameters.Add(p);
    } catch (const InputError& e) {
      throw InputError(source + ": " + e.what());
    }
  }

  if (const YAML::Node inter = root["interference"]) {
    const std::string where = source + ": interference";
    CheckKeys(inter, {"model", "table"}, where);
    const std::string model = inter["model"] ? ReadString(inter["model"], where + ".model")
                                             : std::string("parametric");
    if (model == "parametric") {
      config.interference = InterferenceModel::kParametric;
    } else if (model == "table") {
      config.interference = InterferenceModel::kTable;
    } else {
      throw InputError(where + ".model: '" + model + "' is not 'parametric' or 'table'");
    }
    if (const YAML::Node table = inter["table"]) {
      CheckKeys(table, {"omega1", "omega2", "sigma"}, where + ".table");
      config.sigma_table.omega1 = ReadDoubleList(table["omega1"], where + ".table.omega1");
      config.sigma_table.omega2 = ReadDoubleList(table["omega2"], where + ".table.omega2");
      const YAML::Node rows = table["sigma"];
      if (!rows || !rows.IsSequence()) throw InputError(where + ".table.sigma: expected rows");
      for (size_t i = 0; i < rows.size(); ++i) {
        const auto row =
            ReadDoubleList(rows[i], where + ".table.sigma[" + std::to_string(i) + "]");
        config.sigma_table.sigma.insert(config.sigma_table.sigma.end(), row.begin(), row.end());
      }
      config.sigma_table.Validate(where + ".table");
    }
    if (config.interference == InterferenceModel::kTable && config.sigma_table.empty()) {
      throw InputError(where + ": model 'table' needs a table");
    }
  }

  if (const YAML::Node effects = root["effects"]) {
    if (!effects.IsMap()) throw InputError(source + ": effects: expected a map");
    for (const auto& kv : effects) {
      const std::string name = kv.first.as<std::string>();
      std::map<std::string, ParameterOverride> overrides;
      if (kv.second && kv.second.IsMap()) {
        for (const auto& pv : kv.second) {
          const std::string pname = pv.first.as<std::string>();
          overrides[pname] =
              ReadParameterOverride(pv.second, source + ": effects." + name + "." + pname);
        }
      } else if (kv.second && !kv.second.IsNull()) {
        throw InputError(source + ": effects." + name + ": expected a map of parameters or {}");
      }
      config.effects.emplace_back(name, std::move(overrides));
    }
  }
  return config;
}

VehicleConfig LoadVehicleConfig(const std::string& path) {
  return ParseVehicleConfig(ReadFile(path), path);
}

namespace {

void EmitParameter(YAML::Emitter& out, const Parameter& p, bool default_estimated) {
  out << YAML::Key << p.name.substr(p.name.find('.') == std::string::npos ? 0
                                                                          : p.name.find('.') + 1);
  out << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "value" << YAML::Value << p.value;
  if (std::isfinite(p.lower)) out << YAML::Key << "lower" << YAML::Value << p.lower;
  if (std::isfinite(p.upper)) out << YAML::Key << "upper" << YAML::Value << p.upper;
  out << YAML::Key << "scale" << YAML::Value << p.scale;
  if (p.estimated != default_estimated) {
    out << YAML::Key << "estimated" << YAML::Value << p.estimated;
  }
  if (!p.unit.empty()) out << YAML::Key << "unit" << YAML::Value << p.unit;
  out << YAML::EndMap;
}

}  // namespace

std::string ResolvedConfigYaml(const VehicleConfig& config, const ParameterSet& all) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap;
  out << YAML::Key << "vehicle" << YAML::Value << config.vehicle;
  out << YAML::Key << "known" << YAML::Value << YAML::BeginMap;
  for (int i = 0; i < kAlpha; ++i) EmitParameter(out, all[i], false);
  out << YAML::EndMap;
  out << YAML::Key << "unknown" << YAML::Value << YAML::BeginMap;
  for (int i = kAlpha; i < kNumBaseParameters; ++i) EmitParameter(out, all[i], true);
  out << YAML::EndMap;
  out << YAML::Key << "interference" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "model" << YAML::Value
      << (config.interference == InterferenceModel::kTable ? "table" : "parametric");
  if (!config.sigma_table.empty()) {
    const SigmaTable& t = config.sigma_table;
    out << YAML::Key << "table" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "omega1" << YAML::Value << YAML::Flow << t.omega1;
    out << YAML::Key << "omega2" << YAML::Value << YAML::Flow << t.omega2;
    out << YAML::Key << "sigma" << YAML::Value << YAML::BeginSeq;
    for (size_t i = 0; i < t.omega1.size(); ++i) {
      std::vector<double> row(t.sigma.begin() + i * t.omega2.size(),
                              t.sigma.begin() + (i + 1) * t.omega2.size());
      out << YAML::Flow << row;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndMap;
  out << YAML::Key << "effects" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, overrides] : config.effects) {
    out << YAML::Key << name << YAML::Value << YAML::BeginMap;
    const std::string prefix = name + ".";
    for (int i = kNumBaseParameters; i < all.size(); ++i) {
      if (all[i].name.compare(0, prefix.size(), prefix) == 0) EmitParameter(out, all[i], true);
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace coaxid
