// `coaxid identify --method=ekf` (cli-and-reports.md; ident/ekf/ekf.h):
//
//   coaxid identify --method=ekf --logs=A.csv[,B.csv] --config=F --out=DIR
//       [--validate=C.csv,...] [--holdout_fraction=0.2] [--smoother=true]
//       [--ekf_scale_anchor=d|none] [--ekf_transition=linearised|sensitivities]
//       [--ekf_covariance_pass=true] [--ekf_refinements=10] [--ekf_process_noise=1] [--ekf_process_noise_from_data=true] [--ekf_window_s=1]
//       [--ekf_noise_adaptations=1] [--ekf_gate=1e-6] [--ekf_initial_report=R.json]
//
// Flight logs only. Measurement noise from first differences
// (NoiseFromData), refined from the innovations (--ekf_noise_adaptations).
// Runs the EKF (states and the config's free parameters together) on the
// estimation data (each log's first part, or whole logs when
// --validate is given), then a state-only filter with the parameters held at
// the estimates on the held-out data, and writes
//   DIR/report.json        method "ekf", parameters {value, std, estimated},
//                          fit and validation per channel (1 s window
//                          predictions), the "ekf" section (NIS, scale, ...)
//   DIR/states.csv         state estimates (filtered, smoothed) with std
//   DIR/parameters.csv     parameter history (estimate, std, std at the estimate)
//   DIR/innovations.csv    innovations, sqrt(S_ii), NIS per row
//   DIR/fit_NAME.csv, DIR/validation_NAME.csv   measured and model per channel
//   DIR/config.yaml        the resolved config the run used
//   DIR/estimated_config.yaml   the same with the estimates (a start for the next run)
//   DIR/plots/*.png        parameters, innovations, states, fit (gnuplot; skipped with a
//                          note when missing)
// Everything is computed before anything is written: bad input exits 2 and a
// failed filter (divergence, CVODE) exits 1, both with --out untouched.
// Progress (rows processed, elapsed) goes to stderr, a table of the estimates
// to stdout.
#pragma once

#include <nlohmann/json.hpp>

#include "experiments/cli/identify_run.h"

namespace coaxid {

// Runs the EKF on run's logs, writes run.out and returns its report.json;
// throws InputError (bad input) or ComputationError (failed filter).
nlohmann::json IdentifyEkf(const IdentifyRun& run);

}  // namespace coaxid
