#include "experiments/cli/prior_flag.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "experiments/cli/cli.h"

namespace coaxid {

std::vector<ReportedParameter> ReadReportedParameters(const std::string& path) {
  nlohmann::json report;
  try {
    report = nlohmann::json::parse(ReadFile(path));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not a JSON report (" + e.what() + ")");
  }
  if (!report.is_object() || !report.contains("parameters") ||
      !report["parameters"].is_object()) {
    throw InputError(path + ": no \"parameters\" object (cli-and-reports.md report.json)");
  }
  std::vector<ReportedParameter> out;
  for (const auto& [name, entry] : report["parameters"].items()) {
    if (!entry.is_object() || !entry.contains("value") || !entry["value"].is_number()) continue;
    ReportedParameter p{name, entry["value"].get<double>(),
                        std::numeric_limits<double>::quiet_NaN()};
    if (entry.contains("std") && entry["std"].is_number()) p.std = entry["std"].get<double>();
    out.push_back(p);
  }
  return out;
}

void CheckWithinConfigBounds(const std::string& path, const ReportedParameter& r,
                             const Parameter& p) {
  if (!(std::isfinite(r.value) && r.value >= p.lower && r.value <= p.upper)) {
    throw InputError(path + ": parameters." + r.name + ".value = " + std::to_string(r.value) +
                     " is outside the config's bounds [" + std::to_string(p.lower) + ", " +
                     std::to_string(p.upper) + "]");
  }
}

std::vector<ParameterPrior> ReadPriorFlag(const std::string& spec,
                                          const ParameterSet& parameters,
                                          std::string* description) {
  if (spec.empty()) return {};
  // REPORT.json[:names]: the names follow the last ':' after ".json".
  std::string path = spec;
  std::vector<std::string> names;
  const size_t json_end = spec.rfind(".json");
  if (json_end != std::string::npos && json_end + 5 < spec.size() && spec[json_end + 5] == ':') {
    path = spec.substr(0, json_end + 5);
    names = SplitList(spec.substr(json_end + 6));
    if (names.empty()) throw InputError("--prior=" + spec + ": no parameter name after ':'");
  }
  const std::vector<ReportedParameter> reported = ReadReportedParameters(path);
  auto find = [&](const std::string& name) -> const ReportedParameter* {
    for (const ReportedParameter& p : reported) {
      if (p.name == name) return &p;
    }
    return nullptr;
  };
  std::vector<ParameterPrior> priors;
  auto add = [&](const ReportedParameter& r) {
    CheckWithinConfigBounds(path, r, parameters.Get(r.name));
    priors.push_back({r.name, r.value, r.std});
  };
  for (const std::string& name : names) {
    const ReportedParameter* r = find(name);
    if (!r) throw InputError("--prior: " + path + " gives no value for '" + name + "'");
    if (!parameters.Has(name) || !parameters.Get(name).estimated) {
      throw InputError("--prior: '" + name + "' is not an estimated parameter of the config");
    }
    if (!(std::isfinite(r->std) && r->std > 0)) {
      throw InputError("--prior: " + path + " gives '" + name +
                       "' no std > 0 (held, not estimated or not identifiable there)");
    }
    add(*r);
  }
  if (names.empty()) {
    for (const ReportedParameter& r : reported) {
      if (parameters.Has(r.name) && parameters.Get(r.name).estimated && std::isfinite(r.std) &&
          r.std > 0) {
        add(r);
      }
    }
    if (priors.empty()) {
      throw InputError("--prior: " + path +
                       " gives no estimated parameter of the config a value with a std > 0");
    }
  }
  std::string list;
  for (const ParameterPrior& p : priors) list += (list.empty() ? "" : ", ") + p.name;
  *description = "Gaussian priors (value and std) on " + list + " from " + path + ".";
  return priors;
}

}  // namespace coaxid
