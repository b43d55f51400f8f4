#include "core/report.h"

#include <cmath>

#include "core/atomic_file.h"

namespace coaxid {

void WriteJson(const std::string& path, const nlohmann::json& document) {
  WriteFileAtomically(path, document.dump(2) + "\n");
}

nlohmann::json ParameterValuesJson(const ParameterSet& parameters) {
  nlohmann::json out = nlohmann::json::object();
  for (int i = 0; i < parameters.size(); ++i) out[parameters[i].name] = parameters[i].value;
  return out;
}

nlohmann::json FitJson(const std::map<std::string, FitError>& per_channel) {
  nlohmann::json out = nlohmann::json::object();
  double sum = 0;
  int n = 0;
  for (const auto& [channel, e] : per_channel) {
    out[channel] = {{"rms", e.rms}, {"nrmse", e.nrmse}, {"count", e.count}};
    if (std::isfinite(e.nrmse)) {
      sum += e.nrmse;
      ++n;
    }
  }
  out["overall_nrmse"] = n > 0 ? sum / n : std::nan("");
  return out;
}

}  // namespace coaxid
