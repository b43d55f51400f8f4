// The thrust map and the sigma map (paper Figs. 8-9).
#include "ident/baseline/thrust_map.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.h"
#include "dynamics/interference_loss.h"
#include "tests/ident/baseline/balance_test_util.h"

namespace coaxid {
namespace {

using testing_util::NoiseFree;
using testing_util::SimulatedBalance;

// k = S_s / S_prop of the reference vehicle: (0.02 / 0.17)^2.
constexpr double kAreaRatio = (0.02 * 0.02) / (0.17 * 0.17);
// Noise-free results go through a few divisions and sums of ~10 terms; the
// model's smoothing of the wake speed (kWakeRadicandSmoothing, ~1e-14
// relative) is the largest error: 1e-11 leaves a wide margin.
constexpr double kExact = 1e-11;

ThrustMap NoiseFreeMap() {
  BalanceScenario s;
  s.hold_s = 0.1;
  const std::vector<BalanceData> data = {MakeBalanceData(SimulatedBalance(NoiseFree(s), 1))};
  return FitThrustMap(data, 1.0, kAreaRatio);
}

TEST(ThrustMap, NoiseFreeDataGiveTheTruth) {
  const ThrustMap map = NoiseFreeMap();
  EXPECT_NEAR(map.alpha / -5.9e-5, 1, kExact);
  EXPECT_NEAR(map.beta / -5.3e-5, 1, kExact);
  EXPECT_EQ(map.alpha_holds, 3);  // omega1 in {110, 135, 160}, lower rotor stopped
  EXPECT_EQ(map.beta_holds, 3);
  EXPECT_NEAR(map.sigma0, 0.12, kExact);
  // The map's sigma at every coaxial hold is the truth's parametric sigma.
  int coaxial = 0;
  for (const MapHold& h : map.holds) {
    if (h.role != MapHoldRole::kCoaxial) continue;
    ++coaxial;
    EXPECT_NEAR(h.sigma, InterferenceLoss(0.12, h.omega1, h.omega2), kExact);
  }
  EXPECT_EQ(coaxial, 9);
  // The table: grid {0, 110, 135, 160} on both axes, every coaxial cell
  // measured, sigma = 1 where a rotor is stopped.
  ASSERT_EQ(map.table.omega1.size(), 4u);
  ASSERT_EQ(map.table.omega2.size(), 4u);
  EXPECT_EQ(map.measured_cells, 9);
  EXPECT_EQ(map.filled_cells, 0);
  for (size_t i = 0; i < 4; ++i) {
    for (size_t j = 0; j < 4; ++j) {
      const double w1 = map.table.omega1[i], w2 = map.table.omega2[j];
      EXPECT_NEAR(map.table.sigma[i * 4 + j], InterferenceLoss(0.12, w1, w2), kExact);
      EXPECT_EQ(map.cell_source[i * 4 + j] == SigmaCellSource::kStopped, w1 == 0 || w2 == 0);
    }
  }
  // The loss is largest (sigma0) at equal speeds (model.md decision 1; paper: "about 10 %").
  EXPECT_NEAR(map.max_loss, 0.12, kExact);
  EXPECT_EQ(map.max_loss_omega1, map.max_loss_omega2);
}

TEST(ThrustMap, AssumedCzScalesTheThrustCoefficients) {
  // The paper assumes Cz known; with Cz = 1.5 assumed instead of the truth's
  // 1.0, alpha and beta absorb (1 - k) / (1 - 1.5 k) exactly, and sigma,
  // a ratio of loads, is unchanged.
  BalanceScenario s;
  s.hold_s = 0.1;
  const std::vector<BalanceData> data = {MakeBalanceData(SimulatedBalance(NoiseFree(s), 1))};
  const ThrustMap map = FitThrustMap(data, 1.5, kAreaRatio);
  const double factor = (1 - kAreaRatio) / (1 - 1.5 * kAreaRatio);
  EXPECT_NEAR(map.alpha / (-5.9e-5 * factor), 1, kExact);
  EXPECT_NEAR(map.beta / (-5.3e-5 * factor), 1, kExact);
  EXPECT_NEAR(map.sigma0, 0.12, kExact);
}

TEST(ThrustMap, MissingCellsAreFilledFromTheParametricFit) {
  BalanceScenario s;
  s.hold_s = 0.1;
  Log log = SimulatedBalance(NoiseFree(s), 1);
  // Drop the holds at omega1 = 160 with omega2 = 160 (all angles).
  Log cut = log;
  for (auto& column : cut.values) column.clear();
  for (int k = 0; k < log.NumRows(); ++k) {
    if (log.Column("omega1")[k] == 160 && log.Column("omega2")[k] == 160) continue;
    for (size_t c = 0; c < log.columns.size(); ++c) cut.values[c].push_back(log.values[c][k]);
  }
  const ThrustMap map = FitThrustMap({MakeBalanceData(cut)}, 1.0, kAreaRatio);
  EXPECT_EQ(map.measured_cells, 8);
  EXPECT_EQ(map.filled_cells, 1);
  EXPECT_EQ(map.cell_source[3 * 4 + 3], SigmaCellSource::kParametric);
  EXPECT_NEAR(map.table.sigma[3 * 4 + 3], 1 - 0.12, kExact);
}

TEST(ThrustMap, NoisyStdsAreHonest) {
  // The shipped noise (Z: 0.02 N): alpha and beta within 3 std of the truth,
  // and the std of the same order as the textbook value
  // std(Z) / sqrt(sum n (w^2 (1 - Cz k))^2).
  BalanceScenario s;
  const std::vector<BalanceData> data = {MakeBalanceData(SimulatedBalance(s, 7))};
  const ThrustMap map = FitThrustMap(data, 1.0, kAreaRatio);
  EXPECT_LT(std::fabs(map.alpha + 5.9e-5), 3 * map.alpha_std);
  EXPECT_LT(std::fabs(map.beta + 5.3e-5), 3 * map.beta_std);
  EXPECT_LT(std::fabs(map.sigma0 - 0.12), 3 * map.sigma0_std);
  double sum = 0;
  for (const double w : {110.0, 135.0, 160.0}) sum += 200 * std::pow(w * w * (1 - kAreaRatio), 2);
  const double textbook = 0.02 / std::sqrt(sum);
  EXPECT_NEAR(map.alpha_std / textbook, 1, 0.15);  // the residual variance has ~600 dof
  EXPECT_NEAR(map.z_residual_variance / (0.02 * 0.02), 1, 0.15);
}

TEST(ThrustMap, RefusesDataWithoutSingleRotorHolds) {
  BalanceScenario s;
  s.hold_s = 0.1;
  s.omega1 = {110, 135};  // the lower rotor never runs alone
  const std::vector<BalanceData> data = {MakeBalanceData(SimulatedBalance(s, 1))};
  try {
    FitThrustMap(data, 1.0, kAreaRatio);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lower rotor"), std::string::npos) << e.what();
  }
}

TEST(ThrustMap, RefusesPositiveThrust) {
  BalanceScenario s;
  s.hold_s = 0.1;
  Log log = SimulatedBalance(NoiseFree(s), 1);
  for (double& z : log.values[log.ColumnIndex("Z")]) z = -z;  // z axis up: wrong convention
  try {
    FitThrustMap({MakeBalanceData(log)}, 1.0, kAreaRatio);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sign convention"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace coaxid
