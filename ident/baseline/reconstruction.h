// Reconstruction and validation (paper, sect. 5 and Figs. 10, 12, 13): the
// model outputs X, Y, Z, L, M, N of the linear balance model with the
// estimates, against the measured loads, on the estimation data and on
// held-out data. X and Y are not used in the estimation (paper, sect. 3): they
// validate beta independently of d.
//
// Per channel: rms and nrmse (core/statistics.h, cli-and-reports.md), and the
// paper's relative errors, defined here (the paper does not say) as
//     e_k = |measured_k - model_k| / max_k |measured_k|,
// the error relative to the channel's peak |measured| over the evaluated data
// (all samples pooled), with its mean and max over the samples ("per sample",
// noise included) and over the holds' means ("per hold", noise averaged out,
// which shows the model error itself).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/statistics.h"
#include "ident/baseline/balance_holds.h"
#include "ident/baseline/linear_balance_model.h"

namespace coaxid {

struct Reconstruction {
  const BalanceData* data = nullptr;
  std::array<std::vector<double>, kNumLoadChannels> model;  // per row
};

Reconstruction Reconstruct(const BalanceData& data, const LinearBalanceModel& model,
                           const ThetaVector& theta);

struct ChannelFit {
  FitError error;   // rms, nrmse, count (count 0: channel not measured)
  double peak = 0;  // max |measured|
  double mean_relative_error = 0, max_relative_error = 0;            // per sample
  double hold_mean_relative_error = 0, hold_max_relative_error = 0;  // per hold mean
};
using ChannelFits = std::array<ChannelFit, kNumLoadChannels>;

// Pooled over every reconstruction given. NaN where a channel has no sample.
ChannelFits EvaluateFit(const std::vector<Reconstruction>& parts);

}  // namespace coaxid
