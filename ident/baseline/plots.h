// The figures of the linear_kf baseline, as the paper draws them (Figs.
// 8-13), described for core/plot.h:
//   fig08_thrust_map          mean Z of the delta = 0 holds over omega1, omega2
//   fig09_sigma_map           the interference loss sigma, measured and parametric
//   fig10_estimation_NAME     Z, L, M, N measured (solid) and model (dashed), estimation rows
//   fig11_kalman              trace(P) and the estimates along the filter
//   fig12_validation_NAME     all six loads on held-out data
//   fig13_reconstruction_NAME X and Y (not used in the estimation) on the estimation rows
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/plot.h"
#include "ident/baseline/linear_baseline.h"

namespace coaxid {

// names[i]: a file-name-safe name for estimation data set i (and validation
// data set i in validation_names).
std::vector<NamedFigure> BaselineFigures(const LinearBaselineResult& result,
                                         const std::vector<std::string>& names,
                                         const std::vector<std::string>& validation_names);

}  // namespace coaxid
