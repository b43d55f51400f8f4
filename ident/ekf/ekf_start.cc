#include "ident/ekf/ekf_start.h"

#include <algorithm>
#include <cstdio>

#include "ident/ekf/ekf.h"
#include "ident/noise_weights.h"

namespace coaxid {
EkfStart StartFromEkfPass(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                          double seconds) {
  EkfStart start;
  start.parameters = vehicle.parameters;
  std::vector<EstimationLog> flight;
  for (const EstimationLog& log : logs) {
    if (log.kind == LogKind::kFlight) flight.push_back(FirstSecondsOf(log, seconds));
  }
  if (flight.empty()) {
    start.note = "no flight log for an EKF start";
    return start;
  }
  EkfOptions options;
  options.covariance_pass = false;
  options.smoother = false;
  // No innovation gate: the start runs the declared model, which may lack an
  // effect, and a lacking effect makes the innovations of its channels
  // systematic, not glitches. With the gate, the start failed ("channel q:
  // every sample since 11.83 s rejected") on a flight with undeclared
  // gyroscopic moments, the fit then started from the config and stopped at
  // 5.9 x the noise, and discover added nothing (seed 3042 of the confusion
  // study).
  options.gate_probability = 0;
  const EkfResult pass = RunEkf(vehicle, flight, NoiseFromData(flight), options);
  if (!pass.usable) {
    start.note = "the EKF start failed (" + pass.failure + ")";
    return start;
  }
  for (int i = 0; i < start.parameters.size(); ++i) {
    Parameter& p = start.parameters.mutable_parameter(i);
    if (p.estimated) p.value = std::clamp(pass.parameters[i].value, p.lower, p.upper);
  }
  char note[160];
  std::snprintf(note, sizeof note,
                "starting values from one EKF pass over the first %g s of the flight log(s)",
                seconds);
  start.note = note;
  start.usable = true;
  return start;
}

}  // namespace coaxid
