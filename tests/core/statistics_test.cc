#include "core/statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace coaxid {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Relative tolerance for results that take a few rounded operations
// (sum, division, sqrt): a few ulps of 2.2e-16 each.
constexpr double kRel = 1e-15;

TEST(StatisticsTest, Rms) {
  EXPECT_NEAR(Rms({3, 4}), std::sqrt(12.5), kRel * 4);
  EXPECT_EQ(Rms({1, -1, 1, -1}), 1.0);  // Exact: every operation is exact in binary.
  EXPECT_EQ(Rms({-2}), 2.0);
  EXPECT_NEAR(Rms({3, kNaN, 4, kNaN}), std::sqrt(12.5), kRel * 4);  // NaN skipped, n = 2.
  EXPECT_TRUE(std::isnan(Rms({})));
  EXPECT_TRUE(std::isnan(Rms({kNaN, kNaN})));
}

TEST(StatisticsTest, Mean) {
  EXPECT_EQ(Mean({1, 2, 3, 6}), 3.0);
  EXPECT_EQ(Mean({1, kNaN, 2, 3}), 2.0);  // NaN skipped: divides by 3, not 4.
  EXPECT_EQ(Mean({-0.5}), -0.5);
  EXPECT_TRUE(std::isnan(Mean({})));
  EXPECT_TRUE(std::isnan(Mean({kNaN})));
}

TEST(StatisticsTest, StdDev) {
  // Sample standard deviation (n - 1): squared deviations sum to 32 over 8 values.
  EXPECT_NEAR(StdDev({2, 4, 4, 4, 5, 5, 7, 9}), std::sqrt(32.0 / 7.0), kRel * 3);
  EXPECT_NEAR(StdDev({2, kNaN, 4, 4, 4, 5, 5, 7, 9, kNaN}), std::sqrt(32.0 / 7.0), kRel * 3);
  EXPECT_EQ(StdDev({1, 3}), std::sqrt(2.0));
  EXPECT_TRUE(std::isnan(StdDev({1})));
  EXPECT_TRUE(std::isnan(StdDev({1, kNaN})));
  EXPECT_TRUE(std::isnan(StdDev({})));
}

TEST(StatisticsTest, StdDevWithLargeOffset) {
  // 1e9 + {1, 2, 3}: the one-pass formula sum(x^2) - n mean^2 loses everything
  // (x^2 ~ 1e18, ulp ~ 128); the two-pass one is exact here. Tolerance: the
  // inputs are exact integers, so only the final sqrt rounds.
  EXPECT_NEAR(StdDev({1e9 + 1, 1e9 + 2, 1e9 + 3}), 1.0, 1e-15);
}

TEST(StatisticsTest, FitErrorClosedForm) {
  // Error (0, 0, 0, -1): rms = sqrt(1/4) = 0.5. Spread about the mean 2.5:
  // (2.25 + 0.25 + 0.25 + 2.25) / 4 = 1.25, so nrmse = 0.5 / sqrt(1.25) = 1/sqrt(5).
  const FitError fit = ComputeFitError({1, 2, 3, 4}, {1, 2, 3, 5});
  EXPECT_EQ(fit.count, 4);
  EXPECT_EQ(fit.rms, 0.5);
  EXPECT_NEAR(fit.nrmse, 1.0 / std::sqrt(5.0), kRel);
}

TEST(StatisticsTest, PerfectModelHasZeroError) {
  const std::vector<double> measured = {0.3, -1.2, 4.5, 2.25, 0.0};
  const FitError fit = ComputeFitError(measured, measured);
  EXPECT_EQ(fit.rms, 0.0);  // Exact: every difference is exactly zero.
  EXPECT_EQ(fit.nrmse, 0.0);
  EXPECT_EQ(fit.count, 5);
}

TEST(StatisticsTest, MeanModelHasUnitNrmse) {
  const std::vector<double> measured = {0.3, -1.2, 4.5, 2.25, 0.0, 7.75};
  const std::vector<double> model(measured.size(), Mean(measured));
  const FitError fit = ComputeFitError(measured, model);
  // Same ratio computed two ways; only rounding of the mean may differ (~1 ulp).
  EXPECT_NEAR(fit.nrmse, 1.0, 1e-14);
  EXPECT_NEAR(fit.rms, StdDev(measured) * std::sqrt(5.0 / 6.0), 1e-14);
}

TEST(StatisticsTest, FitErrorSkipsPairsWithNaN) {
  // Pairs 1 and 3 are dropped (one side missing each); what is left is the
  // closed-form case above.
  const FitError fit = ComputeFitError({1, kNaN, 2, 100, 3, 4}, {1, 0, 2, kNaN, 3, 5});
  EXPECT_EQ(fit.count, 4);
  EXPECT_EQ(fit.rms, 0.5);
  EXPECT_NEAR(fit.nrmse, 1.0 / std::sqrt(5.0), kRel);
}

TEST(StatisticsTest, FitErrorUndefinedCases) {
  const FitError none = ComputeFitError({kNaN, 1}, {0, kNaN});
  EXPECT_EQ(none.count, 0);
  EXPECT_TRUE(std::isnan(none.rms));
  EXPECT_TRUE(std::isnan(none.nrmse));
  // A constant measurement has no spread: nrmse is undefined, rms still defined.
  const FitError flat = ComputeFitError({2, 2, 2}, {2, 2, 3});
  EXPECT_EQ(flat.count, 3);
  EXPECT_NEAR(flat.rms, std::sqrt(1.0 / 3.0), kRel);
  EXPECT_TRUE(std::isnan(flat.nrmse));
}

TEST(StatisticsDeathTest, LengthMismatchIsABug) {
  EXPECT_DEATH(ComputeFitError({1, 2}, {1}), "differ in length");
}

}  // namespace
}  // namespace coaxid
