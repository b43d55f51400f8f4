#include "ident/ekf/process_noise_from_data.h"

#include <cstdio>

namespace coaxid {

EkfOptions WithRaisedProcessNoise(const EkfOptions& options, double scale) {
  EkfOptions raised = options;
  for (int i : {kU, kV, kW, kP, kQ, kR}) raised.state_psd[i] *= scale;
  raised.effect_state_psd *= scale;
  return raised;
}

ProcessNoiseFromData ProbeProcessNoise(const Vehicle& vehicle,
                                       const std::vector<EstimationLog>& logs,
                                       const NoiseWeights& noise, const EkfOptions& options,
                                       double probe_s, double factor, int max_raises) {
  ProcessNoiseFromData out;
  out.probe_s = probe_s;
  std::vector<EstimationLog> flight;
  for (const EstimationLog& log : logs) {
    if (log.kind == LogKind::kFlight) flight.push_back(FirstSecondsOf(log, probe_s));
  }
  if (flight.empty()) {
    out.note = "no flight log to probe the process noise on";
    return out;
  }
  EkfOptions probe = options;
  probe.covariance_pass = false;
  probe.smoother = false;
  probe.noise_adaptations = 0;
  probe.progress = nullptr;
  out.found = RunRaisingProcessNoise(
                  probe, &out,
                  [&](const EkfOptions& o) { return RunEkf(vehicle, flight, noise, o); }, nullptr,
                  max_raises, factor)
                  .usable;
  const double scale = out.scale * factor;  // the first scale not tried
  if (!out.found) out.scale = 1.0;
  char text[200];
  if (!out.found) {
    std::snprintf(text, sizeof text,
                  "process noise from the data: no scale up to %g x the default velocity and "
                  "rate PSDs kept the filter consistent over the first %g s; running with the "
                  "default",
                  scale / factor, probe_s);
    out.note = text;
  } else if (out.scale == 1.0) {
    std::snprintf(text, sizeof text,
                  "process noise from the data: the default PSDs keep the filter consistent "
                  "over the first %g s of the flight log(s)", probe_s);
    out.note = text;
  } else {
    std::snprintf(text, sizeof text,
                  "process noise from the data: velocity and rate PSDs raised %g x (the smallest "
                  "power of %g that kept the filter consistent over the first %g s; model error, "
                  "see the NIS and the plausibility verdict); the default lost it: ",
                  out.scale, factor, probe_s);
    out.note = text + out.failures.front();
  }
  return out;
}

EkfResult RunRaisingProcessNoise(const EkfOptions& base, ProcessNoiseFromData* probe,
                                 const std::function<EkfResult(const EkfOptions&)>& run,
                                 const std::function<void(const std::string&)>& say,
                                 int max_raises, double factor) {
  for (int raise = 0;; ++raise) {
    EkfResult result = run(WithRaisedProcessNoise(base, probe->scale));
    if (result.usable || raise >= max_raises) return result;
    probe->failures.push_back(result.failure);
    probe->scale *= factor;
    char scale[32];
    std::snprintf(scale, sizeof scale, "%g", probe->scale);
    probe->note = std::string("process noise from the data: velocity and rate PSDs raised to ") +
                  scale + " x the default after a run lost the filter (" + result.failure + ")";
    if (say) say(probe->note);
  }
}

nlohmann::json ProcessNoiseFromData::ToJson() const {
  return {{"found", found},     {"scale", scale}, {"probe_s", probe_s},
          {"failures", failures}, {"note", note}};
}

}  // namespace coaxid
