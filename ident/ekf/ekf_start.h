// Starting values for the output-error fit from a short EKF pass.
//
// From the config's nominal values a flight-log fit needs a coarse stage
// (0.25 s segments) to reach the right basin; a single filter pass over the
// first seconds of the flight logs lands close enough (measured in
// bench/ident/output_error/flight_only_bench: estimates within ~12 % of the
// truth after 20 s, in ~0.1 s) that the fit can start at its final segment
// length. The pass holds the scale as the EKF does (model.md decision 8),
// runs no smoother and no covariance pass: a start, not a result.
#pragma once

#include <string>
#include <vector>

#include "dynamics/vehicle.h"
#include "ident/estimation_log.h"

namespace coaxid {

struct EkfStart {
  bool usable = false;
  ParameterSet parameters;  // the vehicle's, with the pass's estimates (inside the bounds)
  std::string note;         // for the report: what was used, or why not
};

// One filter pass over the first `seconds` of every flight log in `logs`
// (balance logs are skipped). Not usable (with the reason in note) when
// there is no flight log or the filter fails.
EkfStart StartFromEkfPass(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                          double seconds = 20.0);

}  // namespace coaxid
