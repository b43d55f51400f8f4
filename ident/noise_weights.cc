#include "ident/noise_weights.h"

#include <algorithm>
#include <cmath>

#include <glog/logging.h>

namespace coaxid {
namespace {

struct Accumulator {
  double sum_squares = 0, magnitude = 0;
  long count = 0;
};

NoiseWeights Finish(const std::map<std::string, Accumulator>& acc) {
  NoiseWeights w;
  for (const auto& [name, a] : acc) {
    const double floor = 1e-9 * std::max(a.magnitude, 1e-12);
    const double std = a.count > 0 ? std::sqrt(a.sum_squares / a.count) : floor;
    w.std[name] = std::max(std, floor);
  }
  return w;
}

}  // namespace

double NoiseWeights::For(const std::string& channel) const {
  auto it = std.find(channel);
  CHECK(it != std.end()) << "no noise level for channel " << channel;
  return it->second;
}

NoiseWeights NoiseFromData(const std::vector<EstimationLog>& logs) {
  std::map<std::string, Accumulator> acc;
  for (const EstimationLog& log : logs) {
    // Steady-point balance logs: consecutive rows are different operating points.
    bool steady = log.kind == LogKind::kBalance;
    for (int k = 1; k < log.NumRows() && steady; ++k) {
      steady = log.inputs.input(k) != log.inputs.input(k - 1);
    }
    for (int c = 0; c < log.NumChannels(); ++c) {
      Accumulator& a = acc[log.channel_names[c]];
      const auto column = log.values.col(c);
      double mean = 0;
      int n = 0;
      for (int k = 0; k < column.size(); ++k) {
        if (std::isfinite(column[k])) {
          mean += column[k];
          ++n;
          a.magnitude = std::max(a.magnitude, std::fabs(column[k]));
        }
      }
      mean = n > 0 ? mean / n : 0;
      int previous = -1;  // the channel's previous sample (flight: any earlier row)
      for (int k = 0; k < column.size(); ++k) {
        if (!std::isfinite(column[k])) continue;
        if (steady) {
          a.sum_squares += (column[k] - mean) * (column[k] - mean);
          ++a.count;
        } else if (previous >= 0 &&
                   (log.kind == LogKind::kFlight
                        ? true
                        : previous == k - 1 && log.inputs.input(k) == log.inputs.input(k - 1))) {
          // Flight: between the channel's consecutive samples, whatever its
          // rate (a 20 Hz position in a 200 Hz log: the motion over 50 ms
          // adds to the estimate, which the re-estimates refine). Balance:
          // adjacent rows within a hold only (constant loads).
          const double d = column[k] - column[previous];
          a.sum_squares += 0.5 * d * d;
          ++a.count;
        }
        previous = k;
      }
    }
  }
  return Finish(acc);
}

NoiseWeights NoiseFromResiduals(const std::vector<EstimationLog>& logs,
                                const std::vector<Eigen::MatrixXd>& residuals) {
  CHECK_EQ(logs.size(), residuals.size());
  std::map<std::string, Accumulator> acc;
  for (size_t i = 0; i < logs.size(); ++i) {
    for (int c = 0; c < logs[i].NumChannels(); ++c) {
      Accumulator& a = acc[logs[i].channel_names[c]];
      for (int k = 0; k < residuals[i].rows(); ++k) {
        const double r = residuals[i](k, c);
        const double y = logs[i].values(k, c);
        if (std::isfinite(r)) {
          a.sum_squares += r * r;
          ++a.count;
        }
        if (std::isfinite(y)) a.magnitude = std::max(a.magnitude, std::fabs(y));
      }
    }
  }
  return Finish(acc);
}

NoiseWeights NoiseFromPredictions(const std::vector<EstimationLog>& logs,
                                  const std::vector<Eigen::MatrixXd>& predictions) {
  CHECK_EQ(logs.size(), predictions.size());
  std::vector<Eigen::MatrixXd> residuals;
  for (size_t i = 0; i < logs.size(); ++i) residuals.push_back(logs[i].values - predictions[i]);
  return NoiseFromResiduals(logs, residuals);
}

double MaxRelativeChange(const NoiseWeights& old_noise, const NoiseWeights& new_noise) {
  double change = 0;
  for (const auto& [name, std] : new_noise.std) {
    change = std::max(change, std::fabs(std / old_noise.For(name) - 1));
  }
  return change;
}

}  // namespace coaxid
