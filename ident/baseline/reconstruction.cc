#include "ident/baseline/reconstruction.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace coaxid {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

Reconstruction Reconstruct(const BalanceData& data, const LinearBalanceModel& model,
                           const ThetaVector& theta) {
  Reconstruction r;
  r.data = &data;
  for (auto& channel : r.model) channel.resize(data.NumRows());
  for (const BalanceHold& hold : data.holds) {
    const LoadVector loads = model.Predict(hold.input, theta);  // constant over the hold
    for (int c = 0; c < kNumLoadChannels; ++c) {
      std::fill(r.model[c].begin() + hold.first_row,
                r.model[c].begin() + hold.first_row + hold.num_rows, loads[c]);
    }
  }
  return r;
}

ChannelFits EvaluateFit(const std::vector<Reconstruction>& parts) {
  ChannelFits fits;
  for (int c = 0; c < kNumLoadChannels; ++c) {
    std::vector<double> measured, model;
    for (const Reconstruction& part : parts) {
      const std::vector<double>& z = part.data->loads[c];
      measured.insert(measured.end(), z.begin(), z.end());
      model.insert(model.end(), part.model[c].begin(), part.model[c].end());
    }
    ChannelFit& fit = fits[c];
    fit.error = ComputeFitError(measured, model);
    if (fit.error.count == 0) {
      fit.peak = fit.mean_relative_error = fit.max_relative_error = kNaN;
      fit.hold_mean_relative_error = fit.hold_max_relative_error = kNaN;
      continue;
    }
    double peak = 0;
    for (const double v : measured) {
      if (!std::isnan(v)) peak = std::max(peak, std::fabs(v));
    }
    fit.peak = peak;
    double sum = 0, max = 0;
    int n = 0;
    for (size_t k = 0; k < measured.size(); ++k) {
      if (std::isnan(measured[k]) || std::isnan(model[k])) continue;
      const double e = std::fabs(measured[k] - model[k]);
      sum += e;
      max = std::max(max, e);
      ++n;
    }
    fit.mean_relative_error = peak > 0 ? sum / n / peak : kNaN;
    fit.max_relative_error = peak > 0 ? max / peak : kNaN;
    double hold_sum = 0, hold_max = 0;
    int holds = 0;
    for (const Reconstruction& part : parts) {
      for (const BalanceHold& hold : part.data->holds) {
        if (hold.count[c] == 0) continue;
        const double e = std::fabs(hold.mean[c] - part.model[c][hold.first_row]);
        hold_sum += e;
        hold_max = std::max(hold_max, e);
        ++holds;
      }
    }
    fit.hold_mean_relative_error = peak > 0 && holds > 0 ? hold_sum / holds / peak : kNaN;
    fit.hold_max_relative_error = peak > 0 && holds > 0 ? hold_max / peak : kNaN;
  }
  return fits;
}

}  // namespace coaxid
