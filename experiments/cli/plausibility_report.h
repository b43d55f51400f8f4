// The plausibility verdict (core/plausibility.h) of a report.json, from the
// report's own "parameters", "fit", "validation" and "noise_std": every
// identify method and discover add it the same way and say it on stdout.
#pragma once

#include <nlohmann/json.hpp>

#include "core/parameters.h"
#include "core/plausibility.h"

namespace coaxid {

// The verdict of a report (or of a discovery.json model: the same keys).
PlausibilityVerdict PlausibilityOfReport(const ParameterSet& declared, const nlohmann::json& report);

// Sets (*report)["plausibility"] and returns the verdict.
PlausibilityVerdict AddPlausibility(const ParameterSet& declared, nlohmann::json* report);

// "plausibility: ..." on stdout, each finding on its own line.
void PrintPlausibility(const PlausibilityVerdict& verdict);

}  // namespace coaxid
