// The measurement-noise covariance R of the Kalman filter (paper, eqs. 83-84),
// estimated from the data as the paper does: the loads are constant over a
// constant-input hold, so their spread about the hold's mean is noise. The
// variance of each load channel is pooled over the holds,
//     R_c = sum_h sum_{k in h} (z_kc - mean_hc)^2 / sum_h (n_hc - 1),
// R diagonal (uncorrelated channels, as the paper assumes).
//
// A log of steady operating points has one (averaged) row per hold and no
// within-hold spread: there R cannot be estimated that way, and the residual
// variance of the fitted linear model is used instead, which the report says.
// Every variance is floored at (relative_floor * rms of the channel)^2, so
// that noise-free data still give a positive definite R (STYLE.md item 7) and
// a per-sample information the covariance-form filter can carry next to its
// diffuse prior (linear_kf.h). 1e-4 is well below any strain-gauge balance's
// noise (the paper's is ~1 %; averaged steady points ~0.1 %).
#pragma once

#include <array>
#include <string>

#include "ident/baseline/balance_holds.h"
#include "ident/baseline/linear_balance_model.h"

namespace coaxid {

struct NoiseCovarianceOptions {
  int min_degrees_of_freedom = 10;  // fewer pooled within-hold dof: not estimable from holds
  double relative_floor = 1e-4;     // std floor relative to the channel's rms
  bool IsValid(std::string* why) const;
};

enum class NoiseSource { kAbsent, kWithinHolds, kResidual };
// "absent", "within_holds", "residual".
const char* NoiseSourceName(NoiseSource source);

struct ChannelNoise {
  double variance = 0;  // [N^2] or [(N m)^2]; 0 where absent
  double dof = 0;       // degrees of freedom behind it
  NoiseSource source = NoiseSource::kAbsent;
  bool floored = false;  // raised to the floor (noise-free or nearly so)
};

struct NoiseCovariance {
  std::array<ChannelNoise, kNumLoadChannels> channel;
  LoadVector Variances() const;
};

// Pooled within-hold variances. A channel with fewer than
// min_degrees_of_freedom pooled dof keeps source kAbsent (see SetResidualNoise).
NoiseCovariance WithinHoldNoise(const BalanceData& data,
                                const NoiseCovarianceOptions& options = {});

// For every channel that has data but no within-hold estimate: the residual
// variance of the linear model with parameters theta,
//     sum_k (z_kc - model_kc)^2 / (n_c - parameters_used[c]),
// where parameters_used[c] is how many parameters this channel's samples
// helped fit (their share when several data sets are fitted together).
void SetResidualNoise(const BalanceData& data, const LinearBalanceModel& model,
                      const ThetaVector& theta, const LoadVector& parameters_used,
                      const NoiseCovarianceOptions& options, NoiseCovariance* noise);

}  // namespace coaxid
