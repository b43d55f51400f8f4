// Statistics shared by every estimator (cli-and-reports.md defines nrmse).
#pragma once

#include <vector>

namespace coaxid {

// Root mean square of x, skipping NaN entries. NaN if no finite entry.
double Rms(const std::vector<double>& x);
// Mean of x, skipping NaN. NaN if none.
double Mean(const std::vector<double>& x);
// Sample standard deviation (n-1), skipping NaN. NaN if fewer than two.
double StdDev(const std::vector<double>& x);

// Per-channel fit error of a model output against a measured one. Pairs where
// either value is NaN are skipped.
struct FitError {
  double rms = 0;     // rms(measured - model)
  double nrmse = 0;   // rms(measured - model) / rms(measured - mean(measured))
  int count = 0;      // samples used
};
FitError ComputeFitError(const std::vector<double>& measured, const std::vector<double>& model);

}  // namespace coaxid
