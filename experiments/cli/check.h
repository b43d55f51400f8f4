// `coaxid check` (cli-and-reports.md): reads and validates logs, prints a
// summary of each, and for balance logs the linear_kf excitation check.
//
//   coaxid check --logs=A.csv[,B.csv...] [--config=F]
#pragma once

namespace coaxid {

int RunCheck();

}  // namespace coaxid
