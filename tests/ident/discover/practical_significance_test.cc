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

TEST(PracticalSignificance, WeightedExcessIsInTheFitsWeightedUnits) {
  // count (rms^2 - noise^2) / weight^2: 100 (4 - 1) / 4 + 50 max(0, 0.5 - 1) / 1.
  const std::vector<ChannelResidualTest> tests = {Residual("a", 2, 1, 100),
                                                  Residual("b", std::sqrt(0.5), 1, 50)};
  NoiseWeights w;
  w.std = {{"a", 2.0}, {"b", 1.0}};
  EXPECT_NEAR(WeightedExcess(tests, w), 75, 1e-12);
}

}  // namespace
}  // namespace coaxid
