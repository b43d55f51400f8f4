// Parameters taken from another report.json: `--prior=REPORT.json[:name,...]`
// (Gaussian priors for output_error and discover, initial value and
// covariance for ekf) and `--ekf_initial_report` (start values).
#pragma once

#include <string>
#include <vector>

#include "core/parameters.h"
#include "ident/parameter_prior.h"

namespace coaxid {

// One "parameters" entry of a report: value, and std (NaN when the report
// gives none: held, not estimated or not identifiable there).
struct ReportedParameter {
  std::string name;
  double value = 0;
  double std = 0;
};

// Every numeric-valued entry of path's "parameters" object. Throws
// InputError (naming the file) if it is not a report.json.
std::vector<ReportedParameter> ReadReportedParameters(const std::string& path);

// Throws InputError (naming path and parameter) unless r.value is finite and
// within the config parameter p's bounds.
void CheckWithinConfigBounds(const std::string& path, const ReportedParameter& r,
                             const Parameter& p);

// --prior=REPORT.json[:name,name...]. Without names: every parameter the
// report gives with a std > 0 that the config estimates. Named ones must
// have both there (InputError says which does not). Values must lie within
// the config's bounds. *description: one line for the report's notes.
std::vector<ParameterPrior> ReadPriorFlag(const std::string& spec,
                                          const ParameterSet& parameters,
                                          std::string* description);

}  // namespace coaxid
