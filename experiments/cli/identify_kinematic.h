// `coaxid identify --method=kinematic` (issue 14; ident/kinematic/
// flight_path_reconstruction.h): the data-compatibility check run before any
// aerodynamic fit.
//
//   coaxid identify --method=kinematic --logs=A.csv[,B.csv] --out=DIR [--config=F]
//       [--kinematic_scale_factors=true] [--kinematic_time_offset=true]
//       [--kinematic_segment_s=0.5]
//
// Flight logs only; no vehicle model enters (the config, when given, only
// supplies g). Estimates the gyro and accelerometer biases, their scale
// factors and the time offset of the position, velocity and attitude
// channels behind the IMU, with std, and writes
//   DIR/report.json              method "kinematic", parameters {value, std,
//                                estimated, unit}, correlation, fit per
//                                reconstructed channel, the "kinematic" section
//   DIR/corrected_NAME.csv       each log with the estimated errors removed,
//                                ready for the other methods
//   DIR/fit_NAME.csv             measured and reconstructed channels
//   DIR/plots/fit_NAME.png       the same drawn (gnuplot; skipped with a note)
// A scale factor the logs do not fix (std above 5 %, e.g. s_ax in hover,
// where ax stays near 0) is held at 0 and the fit repeated; the report says
// which. Bad input exits 2, a failed solve 1, both with --out untouched.
#pragma once

#include <nlohmann/json.hpp>

#include "experiments/cli/identify_run.h"

namespace coaxid {

nlohmann::json IdentifyKinematic(const IdentifyRun& run);

}  // namespace coaxid
