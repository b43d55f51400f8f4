// `coaxid compare`: the same logs through the three estimators, one table.
//
//   coaxid compare --logs=A.csv[,B.csv...] --config=F --out=DIR
//       [--validate=C.csv,...] [--holdout_fraction=0.2] [--truth=T.json]
//       [--prior=R.json[:name,...]]
//
// linear_kf runs on the balance logs (skipped, with the reason, when there is
// none), output_error on all logs, ekf on the flight logs (skipped when there
// is none); each through the same code as `coaxid identify`
// (experiments/cli/identify.h), in process, timed. The validation logs
// are shared out the same way; without them each method holds out the final
// part of each of its logs. The scale (model.md decision 8): with balance
// and flight logs, ekf (flight logs only) gets output_error's d and its std
// as a prior (--prior=output_error/report.json:d), so the three methods
// answer the same question; a --prior given to compare goes to output_error
// and ekf instead. Writes
//   DIR/compare.json, DIR/compare.md   the table (experiments/reports/compare_table.h)
//   DIR/plots/estimates.png            estimate vs truth (or vs output_error) per method
//   DIR/linear_kf/, DIR/output_error/, DIR/ekf/   each method's full identify output
// and prints compare.md on stdout. Bad input (a log, the config, the truth
// file, a flag, or a method refusing its data) exits 2 with nothing written
// to DIR: the runs go to a staging folder next to DIR that is moved in only
// when everything succeeded. A method whose estimation fails (exit 1 in
// identify) is reported as failed with the reason; compare fails only when no
// method ran.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace coaxid {

struct CompareRequest {
  std::string logs;      // comma-separated
  std::string validate;  // comma-separated, may be empty
  std::string config;
  std::string out;
  std::string truth;  // truth.json (cli-and-reports.md), may be empty
  double holdout_fraction = 0.2;
  std::string prior;  // --prior for output_error and ekf, may be empty
  bool print_table = true;  // compare.md on stdout
};

// Runs the comparison, writes request.out, returns compare.json.
nlohmann::json Compare(const CompareRequest& request);

// `coaxid compare` from the parsed flags; returns the exit status.
int RunCompare();

}  // namespace coaxid
