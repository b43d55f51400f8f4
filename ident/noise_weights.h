// Output noise standard deviations per channel, the weights of every
// estimator's residuals (R = diag(std^2)): one piece shared by output-error,
// the EKF and the closing loop.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "ident/estimation_log.h"

namespace coaxid {

struct NoiseWeights {
  std::map<std::string, double> std;  // by channel (log column) name, in its units
  // The channel's std; CHECK-fails if unknown.
  double For(const std::string& channel) const;
};

// A first estimate from the data alone: white noise on a smooth signal
// sampled fast shows in first differences, std(diff) / sqrt(2) per channel,
// pooled over logs (in a flight log, differences between a channel's
// consecutive samples, so a channel logged at a lower rate, empty elsewhere,
// is estimated too). Where rows are separate steady points (no smooth signal),
// the spread of the channel is used instead (an upper bound that the
// residual-based re-estimate then refines). Floored at 1e-9 of the channel's
// magnitude so no weight is infinite.
NoiseWeights NoiseFromData(const std::vector<EstimationLog>& logs);

// The classical output-error relaxation: std = rms of the residuals per channel.
// residuals[i] holds (measured - model) for logs[i] (same shape as values).
NoiseWeights NoiseFromResiduals(const std::vector<EstimationLog>& logs,
                                const std::vector<Eigen::MatrixXd>& residuals);

// The same from a model's predictions of the logs (residuals = measured -
// predicted).
NoiseWeights NoiseFromPredictions(const std::vector<EstimationLog>& logs,
                                  const std::vector<Eigen::MatrixXd>& predictions);

// max over channels of |new std / old std - 1|: how far a relaxation moves
// the weights.
double MaxRelativeChange(const NoiseWeights& old_noise, const NoiseWeights& new_noise);

}  // namespace coaxid
