// Outliers in a fit's residuals (issue 14: glitch rows of real logs): per
// channel, the residuals (measured - model) beyond `threshold` noise std,
// and the largest one with its time. A Gaussian residual passes 5 std with
// probability 6e-7, so on a 60 s 200 Hz log a count above a few means
// glitches (or a model that misses that channel in places). Shared by the
// estimators' reports.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ident/estimation_log.h"
#include "ident/noise_weights.h"

namespace coaxid {

struct ChannelOutliers {
  long count = 0;           // |residual| > threshold x noise std
  double largest_std = 0;   // the largest |residual| / noise std
  double largest_at_s = 0;  // its time [s]
  std::string largest_in;   // and its log's source
};

// predictions: one matrix per log (rows x channels, as the log's values).
// Channels with no noise level are skipped.
std::map<std::string, ChannelOutliers> ResidualOutliers(
    const std::vector<EstimationLog>& logs, const std::vector<Eigen::MatrixXd>& predictions,
    const NoiseWeights& noise, double threshold = 5.0);

// {"threshold_std", "channels": {name: {count, largest_std, largest_at_s, largest_in}}}
// with every channel, and a sentence for people (empty when none).
nlohmann::json OutliersJson(const std::map<std::string, ChannelOutliers>& outliers,
                            double threshold = 5.0);
std::string OutliersText(const std::map<std::string, ChannelOutliers>& outliers,
                         double threshold = 5.0);

}  // namespace coaxid
