// The EKF's process noise from the data (issue 17). The process noise stands
// for model error, which a real log holds in an unknown amount. The default
// (EkfOptions::state_psd: a tenth of the sensor noise per sample) suits a
// model that describes the vehicle; on one that does not (a CoaX flight
// without its stabilizer bar) the filter loses the rates within seconds: the
// innovation gate rejects every q sample after 2.7 s, or the innovations
// grow past the divergence test.
//
// The probe: filter passes over the first `probe_s` seconds of the flight
// logs (no smoother, no covariance pass, the run's gate and divergence
// test), the velocity and rate PSDs raised by `factor` per pass until one
// stays consistent; the run then uses the smallest scale that did. On a log
// the model describes the first pass passes and nothing changes. Kinematic
// rows (positions, angles) are exact and keep their PSD.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "dynamics/vehicle.h"
#include "ident/ekf/ekf.h"
#include "ident/estimation_log.h"
#include "ident/noise_weights.h"

namespace coaxid {

struct ProcessNoiseFromData {
  bool found = false;      // a pass stayed consistent (else scale = 1)
  double scale = 1.0;      // on the velocity and rate PSDs
  double probe_s = 0;      // seconds of each flight log probed
  std::vector<std::string> failures;  // why each rejected scale failed
  std::string note;        // for the report
  nlohmann::json ToJson() const;
};

ProcessNoiseFromData ProbeProcessNoise(const Vehicle& vehicle,
                                       const std::vector<EstimationLog>& logs,
                                       const NoiseWeights& noise, const EkfOptions& options,
                                       double probe_s = 20.0, double factor = 10.0,
                                       int max_raises = 6);

// Runs run(options) with the velocity and rate PSDs at probe->scale x
// base's; after a run that loses the filter, raises the scale by `factor`
// and runs again, at most `max_raises` times (each failure and the new scale
// go to *probe, each raise to `say` if given). Returns the last run. The
// probe and the CLI's runs both go through it.
EkfResult RunRaisingProcessNoise(const EkfOptions& base, ProcessNoiseFromData* probe,
                                 const std::function<EkfResult(const EkfOptions&)>& run,
                                 const std::function<void(const std::string&)>& say,
                                 int max_raises = 6, double factor = 10.0);

// options with the process noise of the dynamic rows times `scale`: the
// velocities', the rates' and the effect states' PSD.
EkfOptions WithRaisedProcessNoise(const EkfOptions& options, double scale);

}  // namespace coaxid
