#include "experiments/cli/plausibility_report.h"

#include <cstdio>
#include <map>
#include <set>
#include <string>

namespace coaxid {

PlausibilityVerdict PlausibilityOfReport(const ParameterSet& declared, const nlohmann::json& report,
                                         const std::map<std::string, double>& sensor_noise_std) {
  std::set<std::string> undetermined;
  const std::map<std::string, double> estimates = EstimatesOfReport(
      report.value("parameters", nlohmann::json::object()), declared, &undetermined);
  return JudgePlausibility(declared, estimates, report.value("fit", nlohmann::json()),
                           report.value("validation", nlohmann::json()), sensor_noise_std,
                           undetermined);
}

PlausibilityVerdict AddPlausibility(const ParameterSet& declared,
                                    const std::map<std::string, double>& sensor_noise_std,
                                    nlohmann::json* report) {
  PlausibilityVerdict verdict = PlausibilityOfReport(declared, *report, sensor_noise_std);
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
