// The practical significance of ident/discover/practical_significance.h on
// numbers whose answer is known by hand.
#include "ident/discover/practical_significance.h"

#include <cmath>

#include <gtest/gtest.h>

namespace coaxid {
namespace {

ChannelResidualTest Residual(const std::string& channel, double rms, double noise, int count) {
  ChannelResidualTest t;
  t.channel = channel;
  t.rms = rms;
  t.noise_std = noise;
  t.count = count;
  return t;
}

FitError Rms(double rms) {
  FitError e;
  e.rms = rms;
  return e;
}

TEST(PracticalSignificance, ShareIsTheExcessRemovedInNoiseUnits) {
  // a: noise 1, ms 4 -> 2 (excess 3 -> 1, removes 2 of 3);
  // b: noise 2, ms 8 -> 4 (excess 4 -> 0 in N^2, 1 -> 0 in noise units);
  // c: not one of the candidate's channels (ignored).
  const std::vector<ChannelResidualTest> tests = {Residual("a", 2, 1, 100), Residual("b", std::sqrt(8.0), 2, 50),
                                                  Residual("c", 10, 1, 10)};
  const std::map<std::string, FitError> before = {
      {"a", Rms(2)}, {"b", Rms(std::sqrt(8.0))}, {"c", Rms(10)}};
  const std::map<std::string, FitError> after = {
      {"a", Rms(std::sqrt(2.0))}, {"b", Rms(2)}, {"c", Rms(1)}};
  const ExcessShare s = ShareOfExcessRemoved(before, after, tests, {"a", "b"});
  EXPECT_NEAR(s.excess, 3 + 1, 1e-12);
  EXPECT_NEAR(s.share, (2 + 1) / 4.0, 1e-12);
  EXPECT_NEAR(s.per_channel.at("a"), 2 / 3.0, 1e-12);
  EXPECT_NEAR(s.per_channel.at("b"), 1.0, 1e-12);
  EXPECT_EQ(s.per_channel.count("c"), 0u);
  // A refit that makes a channel worse removes a negative share.
  const ExcessShare worse = ShareOfExcessRemoved(after, before, tests, {"a"});
  EXPECT_LT(worse.share, 0);
}

TEST(PracticalSignificance, NoExcessMeansNoShare) {
  // At the noise floor there is nothing to explain: share 0, not 0 / 0.
  const std::vector<ChannelResidualTest> tests = {Residual("a", 1, 1, 100)};
  const ExcessShare s = ShareOfExcessRemoved({{"a", Rms(1)}}, {{"a", Rms(0.99)}}, tests, {"a"});
  EXPECT_EQ(s.excess, 0);
  EXPECT_EQ(s.share, 0);
}

// The excess a fit leaves in a candidate's channels, known before any refit:
// a: noise 1, ms 4 (3 noise variances); b: below its noise (0, not -0.19);
// c: not the candidate's.
TEST(PracticalSignificance, ChannelsExcessIsTheFitsOwnInNoiseUnits) {
  const std::vector<ChannelResidualTest> tests = {Residual("a", 2, 1, 100),
                                                  Residual("b", 0.9, 1, 100),
                                                  Residual("c", 10, 1, 10)};
  const std::map<std::string, FitError> fit = {{"a", Rms(2)}, {"b", Rms(0.9)}, {"c", Rms(10)}};
  EXPECT_NEAR(ChannelsExcess(fit, tests, {"a", "b"}), 3, 1e-12);
  EXPECT_EQ(ChannelsExcess(fit, tests, {"b"}), 0);
}

TEST(PracticalSignificance, WeightedExcessIsInTheFitsWeightedUnits) {
  // count (rms^2 - noise^2) / weight^2: 100 (4 - 1) / 4 + 50 max(0, 0.5 - 1) / 1.
  const std::vector<ChannelResidualTest> tests = {Residual("a", 2, 1, 100),
                                                  Residual("b", std::sqrt(0.5), 1, 50)};
  NoiseWeights w;
  w.std = {{"a", 2.0}, {"b", 1.0}};
  EXPECT_NEAR(WeightedExcess(tests, w), 75, 1e-12);
}

// Held-out logs judge a change where its gain on the estimation logs lies in
// channels they measure (half of it or more), at their noise too; where it
// lies in channels they do not measure (a balance log's, beside a held-out
// flight), they cannot: NaN.
TEST(PracticalSignificance, HeldOutLogsJudgeWhereTheGainLies) {
  // Estimation: flight channel q (noise 1, ms 1.44 -> 1.2) and balance
  // channel N (noise 1, ms 4 -> 1).
  const std::vector<ChannelResidualTest> estimation_tests = {Residual("q", 1.2, 1, 100),
                                                             Residual("N", 2, 1, 100)};
  const std::map<std::string, FitError> estimation_before = {{"q", Rms(1.2)}, {"N", Rms(2)}};
  const std::map<std::string, FitError> estimation_after = {{"q", Rms(std::sqrt(1.2))},
                                                            {"N", Rms(1)}};
  // Held-out flight: q only, at its noise, made a little worse.
  const std::vector<ChannelResidualTest> held_out_tests = {Residual("q", 1.01, 1, 100)};
  const std::map<std::string, FitError> held_out_before = {{"q", Rms(1.01)}};
  const std::map<std::string, FitError> held_out_after = {{"q", Rms(1.02)}};
  // Removed 0.24 in q and 3 in N: 7 % of the gain in what the held-out measures.
  const ExcessShare both = ShareOfExcessRemoved(estimation_before, estimation_after,
                                                estimation_tests, {"q", "N"});
  EXPECT_NEAR(both.removed.at("q"), 0.24, 1e-12);
  EXPECT_NEAR(both.removed.at("N"), 3, 1e-12);
  EXPECT_TRUE(std::isnan(HeldOutShareOfExcessRemoved(both, held_out_before, held_out_after,
                                                     held_out_tests, {"q", "N"})));
  // All of the gain in q: judged, and the held-out q removes less than nothing.
  const ExcessShare q_only =
      ShareOfExcessRemoved(estimation_before, estimation_after, estimation_tests, {"q"});
  const double judged =
      HeldOutShareOfExcessRemoved(q_only, held_out_before, held_out_after, held_out_tests, {"q"});
  EXPECT_NEAR(judged,
              ShareOfExcessRemoved(held_out_before, held_out_after, held_out_tests, {"q"}).share,
              1e-12);
  EXPECT_LT(judged, 0);
  // A change that removed nothing anywhere is judged (no gain to place).
  const ExcessShare nothing = ShareOfExcessRemoved(estimation_before, estimation_before,
                                                   estimation_tests, {"q", "N"});
  EXPECT_FALSE(std::isnan(HeldOutShareOfExcessRemoved(nothing, held_out_before, held_out_after,
                                                      held_out_tests, {"q", "N"})));
}

}  // namespace
}  // namespace coaxid
