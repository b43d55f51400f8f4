// The plausibility verdict (core/plausibility.h) of a report.json, from the
// report's own "parameters", "fit" and "validation" and the logs' sensor
// noise: every identify method and discover add it the same way and say it
// on stdout.
#pragma once

#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "core/parameters.h"
#include "core/plausibility.h"

namespace coaxid {

// The verdict of a report (or of a discovery.json model: the same keys).
// sensor_noise_std: each channel's sensor noise std from the data
// (NoiseFromData: first differences), not a fit's residual-based weights,
// which grow with the misfit; empty: channels judged by nrmse alone.
PlausibilityVerdict PlausibilityOfReport(const ParameterSet& declared, const nlohmann::json& report,
                                         const std::map<std::string, double>& sensor_noise_std);

// Sets (*report)["plausibility"] and returns the verdict.
PlausibilityVerdict AddPlausibility(const ParameterSet& declared,
                                    const std::map<std::string, double>& sensor_noise_std,
                                    nlohmann::json* report);

// "plausibility: ..." on stdout, each finding on its own line.
void PrintPlausibility(const PlausibilityVerdict& verdict);

}  // namespace coaxid
