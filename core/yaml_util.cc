#include "core/yaml_util.h"

#include <algorithm>
#include <cmath>

#include "core/errors.h"

namespace coaxid {

YAML::Node ParseYaml(const std::string& text, const std::string& source) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(source + ": line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

void CheckKeys(const YAML::Node& node, const std::vector<std::string>& allowed,
               const std::string& where) {
  if (!node.IsMap()) throw InputError(where + ": expected a map");
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      throw InputError(where + ": unknown key '" + key + "' (expected one of " + list + ")");
    }
  }
}

double ReadDouble(const YAML::Node& node, const std::string& where) {
  if (!node.IsScalar()) throw InputError(where + ": expected a number");
  const std::string text = node.as<std::string>();
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(v)) {
    throw InputError(where + ": '" + text + "' is not a finite number");
  }
  return v;
}

int ReadInt(const YAML::Node& node, const std::string& where) {
  const double v = ReadDouble(node, where);
  if (v != std::floor(v) || std::fabs(v) > 2e9) {
    throw InputError(where + ": expected a whole number");
  }
  return static_cast<int>(v);
}

bool ReadBool(const YAML::Node& node, const std::string& where) {
  try {
    return node.as<bool>();
  } catch (const YAML::Exception&) {
    throw InputError(where + ": expected true or false");
  }
}

std::string ReadString(const YAML::Node& node, const std::string& where) {
  if (!node.IsScalar()) throw InputError(where + ": expected a text value");
  return node.as<std::string>();
}

std::vector<double> ReadDoubleList(const YAML::Node& node, const std::string& where) {
  if (!node.IsSequence()) throw InputError(where + ": expected a list of numbers");
  std::vector<double> out;
  for (size_t i = 0; i < node.size(); ++i) {
    out.push_back(ReadDouble(node[i], where + "[" + std::to_string(i) + "]"));
  }
  return out;
}

ParameterOverride ReadParameterOverride(const YAML::Node& node, const std::string& where) {
  ParameterOverride o;
  if (node.IsScalar()) {
    o.value = ReadDouble(node, where);
    return o;
  }
  CheckKeys(node, {"value", "lower", "upper", "scale", "estimated", "unit"}, where);
  if (node["value"]) o.value = ReadDouble(node["value"], where + ".value");
  if (node["lower"]) o.lower = ReadDouble(node["lower"], where + ".lower");
  if (node["upper"]) o.upper = ReadDouble(node["upper"], where + ".upper");
  if (node["scale"]) o.scale = ReadDouble(node["scale"], where + ".scale");
  if (node["estimated"]) o.estimated = ReadBool(node["estimated"], where + ".estimated");
  if (node["unit"]) o.unit = ReadString(node["unit"], where + ".unit");
  return o;
}

}  // namespace coaxid
