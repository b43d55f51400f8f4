#include "ident/baseline/noise_covariance.h"

#include <cmath>
#include <string>

namespace coaxid {
namespace {

// rms of a channel's finite values (0 if none).
double ChannelRms(const std::vector<double>& z) {
  double sum = 0;
  int n = 0;
  for (const double v : z) {
    if (std::isnan(v)) continue;
    sum += v * v;
    ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : 0.0;
}

void ApplyFloor(const BalanceData& data, int c, const NoiseCovarianceOptions& options,
                ChannelNoise* noise) {
  const double rms = ChannelRms(data.loads[c]);
  // An all-zero channel has no scale of its own: floor relative to 1 (SI unit).
  const double floor_std = options.relative_floor * (rms > 0 ? rms : 1.0);
  if (!(noise->variance >= floor_std * floor_std)) {
    noise->variance = floor_std * floor_std;
    noise->floored = true;
  }
}

}  // namespace

bool NoiseCovarianceOptions::IsValid(std::string* why) const {
  if (min_degrees_of_freedom < 1) return *why = "min_degrees_of_freedom must be >= 1", false;
  if (!(relative_floor > 0)) return *why = "relative_floor must be > 0", false;
  return true;
}

const char* NoiseSourceName(NoiseSource source) {
  switch (source) {
    case NoiseSource::kAbsent:
      return "absent";
    case NoiseSource::kWithinHolds:
      return "within_holds";
    case NoiseSource::kResidual:
      return "residual";
  }
  return "";
}

LoadVector NoiseCovariance::Variances() const {
  LoadVector v;
  for (int c = 0; c < kNumLoadChannels; ++c) v[c] = channel[c].variance;
  return v;
}

NoiseCovariance WithinHoldNoise(const BalanceData& data, const NoiseCovarianceOptions& options) {
  NoiseCovariance noise;
  for (int c = 0; c < kNumLoadChannels; ++c) {
    double squares = 0;
    int dof = 0;
    for (const BalanceHold& hold : data.holds) {
      if (hold.count[c] < 2) continue;
      squares += hold.sum_squares[c];
      dof += hold.count[c] - 1;
    }
    ChannelNoise& n = noise.channel[c];
    if (dof < options.min_degrees_of_freedom) continue;
    n.variance = squares / dof;
    n.dof = dof;
    n.source = NoiseSource::kWithinHolds;
    ApplyFloor(data, c, options, &n);
  }
  return noise;
}

void SetResidualNoise(const BalanceData& data, const LinearBalanceModel& model,
                      const ThetaVector& theta, const LoadVector& parameters_used,
                      const NoiseCovarianceOptions& options, NoiseCovariance* noise) {
  LoadVector squares{};
  LoadCounts counts{};
  // The model is constant over a hold: the row-level residual sum of squares
  // is the within-hold part plus n (mean - model)^2.
  for (const BalanceHold& hold : data.holds) {
    const LoadVector predicted = model.Predict(hold.input, theta);
    for (int c = 0; c < kNumLoadChannels; ++c) {
      if (hold.count[c] == 0) continue;
      const double r = hold.mean[c] - predicted[c];
      squares[c] += hold.sum_squares[c] + hold.count[c] * r * r;
      counts[c] += hold.count[c];
    }
  }
  for (int c = 0; c < kNumLoadChannels; ++c) {
    ChannelNoise& n = noise->channel[c];
    if (n.source != NoiseSource::kAbsent || counts[c] == 0) continue;
    const double dof = counts[c] - parameters_used[c];
    if (!(dof > 0)) continue;
    n.variance = squares[c] / dof;
    n.dof = dof;
    n.source = NoiseSource::kResidual;
    n.floored = false;
    ApplyFloor(data, c, options, &n);
  }
}

}  // namespace coaxid
