#include "ident/residual_outliers.h"

#include <cmath>
#include <cstdio>

namespace coaxid {

std::map<std::string, ChannelOutliers> ResidualOutliers(
    const std::vector<EstimationLog>& logs, const std::vector<Eigen::MatrixXd>& predictions,
    const NoiseWeights& noise, double threshold) {
  std::map<std::string, ChannelOutliers> out;
  for (size_t i = 0; i < logs.size() && i < predictions.size(); ++i) {
    const EstimationLog& log = logs[i];
    for (int c = 0; c < log.NumChannels(); ++c) {
      const auto it = noise.std.find(log.channel_names[c]);
      if (it == noise.std.end() || !(it->second > 0)) continue;
      ChannelOutliers& o = out[log.channel_names[c]];
      for (int k = 0; k < log.NumRows(); ++k) {
        const double r = std::fabs(log.values(k, c) - predictions[i](k, c)) / it->second;
        if (!std::isfinite(r)) continue;
        if (r > threshold) ++o.count;
        if (r > o.largest_std) {
          o.largest_std = r;
          o.largest_at_s = log.inputs.time(k);
          o.largest_in = log.source;
        }
      }
    }
  }
  return out;
}

nlohmann::json OutliersJson(const std::map<std::string, ChannelOutliers>& outliers,
                            double threshold) {
  nlohmann::json channels = nlohmann::json::object();
  for (const auto& [name, o] : outliers) {
    channels[name] = {{"count", o.count},
                      {"largest_std", o.largest_std},
                      {"largest_at_s", o.largest_at_s},
                      {"largest_in", o.largest_in}};
  }
  return {{"threshold_std", threshold},
          {"definition", "residuals (measured - model) beyond threshold_std noise std, per "
                         "channel; a Gaussian residual passes 5 std with probability 6e-7"},
          {"channels", channels}};
}

std::string OutliersText(const std::map<std::string, ChannelOutliers>& outliers,
                         double threshold) {
  std::string list;
  for (const auto& [name, o] : outliers) {
    if (o.count == 0) continue;
    char buffer[160];
    std::snprintf(buffer, sizeof buffer, "%s%s %ld (largest %.3g std at t = %.3f s)",
                  list.empty() ? "" : ", ", name.c_str(), o.count, o.largest_std,
                  o.largest_at_s);
    list += buffer;
  }
  if (list.empty()) return "";
  char head[96];
  std::snprintf(head, sizeof head, "residuals beyond %g noise std: ", threshold);
  return head + list +
         " (glitch rows? --huber fits robustly; the EKF's innovation gate rejects them)";
}

}  // namespace coaxid
