#include "experiments/cli/plausibility_report.h"

#include <cstdio>
#include <map>
#include <string>

namespace coaxid {

PlausibilityVerdict PlausibilityOfReport(const ParameterSet& declared,
                                         const nlohmann::json& report) {
  // output_error and discover: "noise_std"; ekf: its measurement noise.
  std::map<std::string, double> noise;
  nlohmann::json noise_json = report.value("noise_std", nlohmann::json::object());
  if (noise_json.empty() && report.contains("ekf")) {
    noise_json = report["ekf"].value("measurement_noise", nlohmann::json::object())
                     .value("std", nlohmann::json::object());
  }
  for (auto it = noise_json.begin(); it != noise_json.end(); ++it) {
    if (it.value().is_number()) noise[it.key()] = it.value().get<double>();
  }
  return JudgePlausibility(declared,
                           EstimatesOfReport(report.value("parameters", nlohmann::json::object())),
                           report.value("fit", nlohmann::json()),
                           report.value("validation", nlohmann::json()), noise);
}

PlausibilityVerdict AddPlausibility(const ParameterSet& declared, nlohmann::json* report) {
  PlausibilityVerdict verdict = PlausibilityOfReport(declared, *report);
  (*report)["plausibility"] = verdict.ToJson();
  return verdict;
}

void PrintPlausibility(const PlausibilityVerdict& verdict) {
  if (verdict.DescribesVehicle()) {
    std::printf("plausibility: %s\n", verdict.Summary().c_str());
    return;
  }
  std::printf("plausibility: THE MODEL DOES NOT DESCRIBE THIS VEHICLE (%zu finding(s)):\n",
              verdict.findings.size());
  for (const PlausibilityFinding& f : verdict.findings) std::printf("  - %s\n", f.text.c_str());
  std::printf("  Estimates from such a fit are not the vehicle's: the model lacks something "
              "(try `coaxid discover`), or the logs do not excite what it needs.\n");
}

}  // namespace coaxid
