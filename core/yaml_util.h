// Small helpers for reading YAML configs with messages that name the file and
// the entry. Every config reader (vehicle, scenario, study) uses these.
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "core/vehicle_config.h"

namespace coaxid {

// Parses a YAML document; throws InputError "FILE: line L: ..." on syntax errors.
YAML::Node ParseYaml(const std::string& text, const std::string& source);

// Throws InputError "WHERE: unknown key 'k' (expected one of ...)" if `node`
// (a map) holds a key not in `allowed`.
void CheckKeys(const YAML::Node& node, const std::vector<std::string>& allowed,
               const std::string& where);

double ReadDouble(const YAML::Node& node, const std::string& where);
int ReadInt(const YAML::Node& node, const std::string& where);
bool ReadBool(const YAML::Node& node, const std::string& where);
std::string ReadString(const YAML::Node& node, const std::string& where);
std::vector<double> ReadDoubleList(const YAML::Node& node, const std::string& where);

// A parameter entry: a number (the value) or a map with value, lower, upper,
// scale, estimated, unit.
ParameterOverride ReadParameterOverride(const YAML::Node& node, const std::string& where);

}  // namespace coaxid
