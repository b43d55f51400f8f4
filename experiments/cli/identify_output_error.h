// `coaxid identify --method=output_error` (cli-and-reports.md):
//
//   coaxid identify --method=output_error --logs=a.csv,b.csv --config=F --out=DIR
//       [--validate=C.csv,...] [--holdout_fraction=0.2] [--segment_s=1]
//       [--noise_relaxations=2] [--huber=0] [--start=config|linear_kf]
//
// Fits every free parameter of the config jointly to all logs (balance and
// flight mixed), then writes DIR/report.json (estimates with Cramér-Rao
// stds, correlation, identifiability verdict, fit and validation errors per
// channel, convergence), DIR/config.yaml (resolved, with the estimates),
// DIR/fit_NAME.csv and DIR/validation_NAME.csv (measured and model per
// channel) and DIR/plots/*.png. Everything is read and checked first; a solve
// that fails exits 1 and writes nothing.
#pragma once

#include <nlohmann/json.hpp>

#include "experiments/cli/identify_run.h"

namespace coaxid {

// Runs the method on run's logs, writes run.out, returns its report.json.
nlohmann::json IdentifyOutputError(const IdentifyRun& run);

}  // namespace coaxid
