// Segmentation of balance logs into constant-input holds.
#include "ident/baseline/balance_holds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/errors.h"
#include "tests/ident/baseline/balance_test_util.h"

namespace coaxid {
namespace {

using testing_util::NoiseFree;
using testing_util::SimulatedBalance;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(BalanceHolds, TimeSeriesGivesOneHoldPerStaircaseStep) {
  BalanceScenario s;
  s.hold_s = 0.5;  // 50 rows per hold at 100 Hz
  const Log log = SimulatedBalance(s, 1);
  const BalanceData data = MakeBalanceData(log);
  // 4 omega1 x (1 hold with the lower rotor stopped + 3 omega2 x 9 swashplate pairs).
  ASSERT_EQ(data.NumHolds(), 4 * (1 + 3 * 9));
  int rows = 0;
  for (const BalanceHold& hold : data.holds) {
    EXPECT_EQ(hold.num_rows, 50);
    EXPECT_EQ(hold.first_row, rows);
    rows += hold.num_rows;
    for (int c = 0; c < kNumLoadChannels; ++c) EXPECT_EQ(hold.count[c], 50);
  }
  EXPECT_EQ(rows, log.NumRows());
  EXPECT_FALSE(data.steady_points);
}

TEST(BalanceHolds, MeansAndSpreadOfEachHold) {
  BalanceScenario s;
  s.hold_s = 0.2;
  const Log log = SimulatedBalance(NoiseFree(s), 1);
  BalanceData data = MakeBalanceData(log);
  // Noise-free: each hold's loads are constant, so the mean is the value and
  // the spread vanishes, up to the rounding of a sum of 20 values (a few ulps).
  for (const BalanceHold& hold : data.holds) {
    for (int c = 0; c < kNumLoadChannels; ++c) {
      const double v = data.loads[c][hold.first_row];
      EXPECT_NEAR(hold.mean[c], v, 1e-14 * std::fabs(v));
      EXPECT_LE(hold.sum_squares[c], 20 * std::pow(1e-14 * v, 2));
    }
  }
  // A hand-made hold: mean and squared deviations of 1, 2, NaN, 3 skip the NaN.
  Log small;
  small.kind = LogKind::kBalance;
  small.source = "small.csv";
  small.SetColumn("t", {0, 1, 2, 3, 4});
  small.SetColumn("omega1", {100, 100, 100, 100, 120});
  small.SetColumn("omega2", {100, 100, 100, 100, 100});
  small.SetColumn("delta_cx", {0, 0, 0, 0, 0});
  small.SetColumn("delta_cy", {0, 0, 0, 0, 0});
  small.SetColumn("Z", {1, 2, kNaN, 3, 7});
  data = MakeBalanceData(small);
  ASSERT_EQ(data.NumHolds(), 2);
  EXPECT_EQ(data.holds[0].num_rows, 4);
  EXPECT_EQ(data.holds[0].count[kLoadZ], 3);
  EXPECT_EQ(data.holds[0].mean[kLoadZ], 2.0);
  EXPECT_EQ(data.holds[0].sum_squares[kLoadZ], 2.0);
  EXPECT_EQ(data.holds[0].count[kLoadN], 0);  // absent column
  EXPECT_FALSE(data.has_channel[kLoadN]);
  EXPECT_TRUE(std::isnan(data.holds[0].mean[kLoadN]));
}

TEST(BalanceHolds, SteadyPointsAreOneRowHolds) {
  Log log;
  log.kind = LogKind::kBalance;
  log.metadata["layout"] = "steady_points";
  log.SetColumn("t", {0, 1, 2});
  log.SetColumn("omega1", {100, 100, 120});
  log.SetColumn("omega2", {100, 100, 100});
  log.SetColumn("delta_cx", {0, 0, 0});
  log.SetColumn("delta_cy", {0, 0, 0});
  log.SetColumn("Z", {-1, -1.1, -2});
  const BalanceData data = MakeBalanceData(log);
  EXPECT_TRUE(data.steady_points);
  // The first two points share their inputs but are separate averaged points.
  EXPECT_EQ(data.NumHolds(), 3);
}

TEST(BalanceHolds, PartsKeepTheirLogRows) {
  BalanceScenario s;
  s.hold_s = 0.5;
  const Log log = SimulatedBalance(s, 2);
  const int cut = HoldoutStartRow(log, 0.2);
  // Holds are 50 rows: the cut is on a hold boundary, near 80 % of the rows.
  EXPECT_EQ(cut % 50, 0);
  EXPECT_NEAR(cut, 0.8 * log.NumRows(), 25);
  const BalanceData tail = MakeBalanceData(log, cut);
  EXPECT_EQ(tail.first_log_row, cut);
  EXPECT_EQ(tail.NumRows(), log.NumRows() - cut);
  EXPECT_EQ(tail.holds.front().num_rows, 50);  // no hold split
  EXPECT_NE(tail.source.find("rows"), std::string::npos);
  EXPECT_EQ(HoldoutStartRow(log, 0.0), log.NumRows());
  EXPECT_THROW(HoldoutStartRow(log, 1.0), InputError);
  EXPECT_THROW(HoldoutStartRow(log, -0.1), InputError);
}

TEST(BalanceHolds, RefusesFlightLogs) {
  Log log;
  log.kind = LogKind::kFlight;
  log.source = "f.csv";
  log.SetColumn("t", {0});
  try {
    MakeBalanceData(log);
    FAIL() << "a flight log was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("balance"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace coaxid
