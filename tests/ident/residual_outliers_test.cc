// ResidualOutliers (ident/residual_outliers.h): counts exactly the residuals
// beyond the threshold per channel, finds the largest with its time, skips
// missing values, and says nothing when there are none.
#include "ident/residual_outliers.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/log.h"

namespace coaxid {
namespace {

TEST(ResidualOutliers, CountsTheSpikesAndFindsTheLargest) {
  const int n = 2000;
  Log log;
  log.kind = LogKind::kFlight;
  log.source = "spiky";
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  for (const char* c : {"t", "omega1", "omega2", "delta_cx", "delta_cy", "phi", "theta", "psi", "p",
                        "q", "r"}) {
    log.columns.push_back(c);
    std::vector<double> v(n);
    for (int k = 0; k < n; ++k) v[k] = std::string(c) == "t" ? 0.005 * k : 0.0;
    log.values.push_back(v);
  }
  EstimationLog est = MakeEstimationLog(log);
  NoiseWeights noise;
  for (const std::string& c : est.channel_names) noise.std[c] = 0.01;
  // The model predicts 0; the measurements are white noise of std 0.01
  // truncated at 4 std, plus three spikes in q and a missing value in r.
  for (int c = 0; c < est.NumChannels(); ++c) {
    for (int k = 0; k < n; ++k) est.values(k, c) = 0.01 * std::clamp(normal(rng), -4.0, 4.0);
  }
  const int q = static_cast<int>(std::find(est.channel_names.begin(), est.channel_names.end(), "q") -
                                 est.channel_names.begin());
  const int r = static_cast<int>(std::find(est.channel_names.begin(), est.channel_names.end(), "r") -
                                 est.channel_names.begin());
  est.values(100, q) = 0.2;    // 20 std
  est.values(700, q) = -0.9;   // 90 std, the largest, at t = 3.5 s
  est.values(1500, q) = 0.06;  // 6 std
  est.values(10, r) = std::numeric_limits<double>::quiet_NaN();
  const Eigen::MatrixXd model = Eigen::MatrixXd::Zero(n, est.NumChannels());
  const auto out = ResidualOutliers({est}, {model}, noise);
  ASSERT_EQ(out.size(), static_cast<size_t>(est.NumChannels()));
  EXPECT_EQ(out.at("q").count, 3);
  EXPECT_NEAR(out.at("q").largest_std, 90.0, 1e-9);
  EXPECT_NEAR(out.at("q").largest_at_s, 3.5, 1e-12);
  EXPECT_EQ(out.at("q").largest_in, "spiky");
  for (const auto& [name, o] : out) {
    if (name == "q") continue;
    EXPECT_EQ(o.count, 0) << name;
    EXPECT_LE(o.largest_std, 4.0 + 1e-12) << name;
  }
  const std::string text = OutliersText(out);
  EXPECT_NE(text.find("q 3 (largest 90 std at t = 3.500 s)"), std::string::npos) << text;
  EXPECT_EQ(OutliersJson(out)["channels"]["q"]["count"], 3);
  // Without the spikes: nothing to say.
  est.values(100, q) = est.values(700, q) = est.values(1500, q) = 0;
  EXPECT_EQ(OutliersText(ResidualOutliers({est}, {model}, noise)), "");
}

}  // namespace
}  // namespace coaxid
