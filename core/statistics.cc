#include "core/statistics.h"

#include <glog/logging.h>

#include <cmath>
#include <limits>
#include <vector>

namespace coaxid {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

double Rms(const std::vector<double>& x) {
  double sum_squares = 0;
  int count = 0;
  for (const double v : x) {
    if (std::isnan(v)) continue;
    sum_squares += v * v;
    ++count;
  }
  return count > 0 ? std::sqrt(sum_squares / count) : kNaN;
}

double Mean(const std::vector<double>& x) {
  double sum = 0;
  int count = 0;
  for (const double v : x) {
    if (std::isnan(v)) continue;
    sum += v;
    ++count;
  }
  return count > 0 ? sum / count : kNaN;
}

double StdDev(const std::vector<double>& x) {
  // Two passes (mean, then squared deviations): the one-pass sum-of-squares
  // formula cancels catastrophically for signals with a large offset, such as
  // rotor speeds around 150 rad/s varying by 0.1 rad/s.
  const double mean = Mean(x);
  double sum_squares = 0;
  int count = 0;
  for (const double v : x) {
    if (std::isnan(v)) continue;
    sum_squares += (v - mean) * (v - mean);
    ++count;
  }
  return count >= 2 ? std::sqrt(sum_squares / (count - 1)) : kNaN;
}

FitError ComputeFitError(const std::vector<double>& measured, const std::vector<double>& model) {
  CHECK_EQ(measured.size(), model.size()) << "measured and model outputs differ in length";
  // Only pairs where both values exist; the same pairs give the mean of the
  // measurement, so nrmse compares the model with the best constant on those samples.
  double sum_measured = 0;
  int count = 0;
  for (size_t k = 0; k < measured.size(); ++k) {
    if (std::isnan(measured[k]) || std::isnan(model[k])) continue;
    sum_measured += measured[k];
    ++count;
  }
  FitError fit;
  fit.count = count;
  if (count == 0) {
    fit.rms = kNaN;
    fit.nrmse = kNaN;
    return fit;
  }
  const double mean = sum_measured / count;
  double sum_error = 0;
  double sum_spread = 0;
  for (size_t k = 0; k < measured.size(); ++k) {
    if (std::isnan(measured[k]) || std::isnan(model[k])) continue;
    const double error = measured[k] - model[k];
    const double spread = measured[k] - mean;
    sum_error += error * error;
    sum_spread += spread * spread;
  }
  fit.rms = std::sqrt(sum_error / count);
  // A constant measurement has no spread to normalise by: nrmse is undefined (NaN),
  // rather than infinity or 0/0 depending on rounding.
  fit.nrmse = sum_spread > 0 ? std::sqrt(sum_error / sum_spread) : kNaN;
  return fit;
}

}  // namespace coaxid
