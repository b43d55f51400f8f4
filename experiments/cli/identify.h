// `coaxid identify` (cli-and-reports.md) and the linear_kf part of
// `coaxid check`.
//
//   coaxid identify --method=linear_kf --logs=A.csv[,B.csv] --config=F --out=DIR
//                   [--validate=C.csv,...] [--holdout_fraction=0.2] [--process_noise=0]
//
// writes DIR/report.json, DIR/config.yaml (the resolved config), the CSV
// tables behind the paper's Figs. 8-13 (thrust_map.csv, sigma_map.csv,
// kf_history.csv, reconstruction_NAME.csv) and DIR/plots/*.png (gnuplot; when
// it is missing the report says "plots skipped"). Every input is read and
// checked, and the whole estimation done, before anything is written: on bad
// input (InputError, exit 2) --out is left untouched. Progress goes to stderr,
// a short table of the estimates to stdout.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/log.h"
#include "experiments/cli/identify_run.h"

namespace coaxid {

// Runs `identify` from the parsed flags. Returns the exit status; throws
// InputError (bad input) or ComputationError (a failed estimation).
int RunIdentify();

// The identify run the flags describe (--method, --logs, --validate,
// --config, --out, --holdout_fraction).
IdentifyRun IdentifyRunFromFlags();

// Runs one method (linear_kf, output_error or ekf), writes run.out and
// returns its report.json document. Throws InputError / ComputationError
// with run.out untouched.
nlohmann::json Identify(const IdentifyRun& run);

// The linear_kf method alone (what Identify runs for method linear_kf).
nlohmann::json IdentifyLinearKf(const IdentifyRun& run);

// The linear_kf excitation check of each log (and of all balance logs
// together when there are several), as text for `coaxid check`. Flight logs
// get a line saying the check applies to balance logs only. config_path may
// be empty: the reference vehicle's d and scales are then used (the verdict
// does not depend on them; the eigenvalues do).
std::string LinearKfCheckText(const std::vector<Log>& logs, const std::string& config_path);

}  // namespace coaxid
