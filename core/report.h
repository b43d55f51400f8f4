// Reports: JSON documents (report.json, truth.json, discovery.json of
// ../shared/spec/cli-and-reports.md), written atomically.
#pragma once

#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "core/parameters.h"
#include "core/statistics.h"

namespace coaxid {

// Writes pretty-printed JSON atomically. Throws InputError if it cannot.
void WriteJson(const std::string& path, const nlohmann::json& document);

// {"name": value, ...} for every parameter of the set.
nlohmann::json ParameterValuesJson(const ParameterSet& parameters);

// The "fit" / "validation" object: {"Z": {"rms":..,"nrmse":..,"count":..}, ...,
// "overall_nrmse": mean of the channels' nrmse}.
nlohmann::json FitJson(const std::map<std::string, FitError>& per_channel);

}  // namespace coaxid
