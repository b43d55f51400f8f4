// One identification run as data rather than flags, so that `coaxid identify`,
// `coaxid compare` and `coaxid demo` go through the same code: each method's
// function reads its logs, estimates, writes run.out (report.json, CSVs,
// plots) only once everything succeeded, and returns the report.json
// document. Method-specific settings (--segment_s, --smoother, ...) still come
// from their flags, so compare and demo honour them too.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace coaxid {

struct IdentifyRun {
  std::string method;    // linear_kf, output_error or ekf
  std::string logs;      // comma-separated estimation logs
  std::string validate;  // comma-separated held-out logs (empty: hold out a final part)
  std::string config;    // vehicle config (YAML)
  std::string out;       // output folder
  double holdout_fraction = 0.2;
  std::string prior;     // --prior=REPORT.json[:name,...] (output_error, ekf); empty: none
  bool print_estimates = true;  // the method's table of estimates on stdout
};

}  // namespace coaxid
