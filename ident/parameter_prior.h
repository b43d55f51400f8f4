// Gaussian priors on parameters, e.g. from another report (a balance fit's d
// and its std): output_error adds them as prior residuals (value - mean) /
// std, the EKF starts from them (initial value and covariance). A prior on a
// member of the scale group fixes the scale (ident/scale_gauge.h).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/parameters.h"

namespace coaxid {

struct ParameterPrior {
  std::string name;
  double value = 0;
  double std = 0;  // > 0
};

std::vector<std::string> PriorNames(const std::vector<ParameterPrior>& priors);

// Sets each prior's parameter to the prior's value (clamped to its bounds):
// the start of the fit.
void StartAtPriors(const std::vector<ParameterPrior>& priors, ParameterSet* parameters);

// The whitened prior residuals r = A (p - b) over the scaled free parameters
// p = value / scale: one row per prior on a free parameter. A is rows x P.
struct ScaledPriorRows {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;  // size P (0 where no prior)
};
ScaledPriorRows PriorRows(const std::vector<ParameterPrior>& priors,
                          const std::vector<std::string>& free_names,
                          const Eigen::VectorXd& free_scales);

}  // namespace coaxid
