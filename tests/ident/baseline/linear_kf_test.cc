// The regressors of eq. 70 and the Kalman recursion (eqs. 80-82) against two
// independent routes: the nonlinear model of dynamics/ (for the regressors)
// and the batch least-squares solution by QR (for the filter).
#include "ident/baseline/linear_kf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "dynamics/interference_loss.h"
#include "ident/baseline/noise_covariance.h"
#include "ident/baseline/thrust_map.h"
#include "tests/ident/baseline/balance_test_util.h"

namespace coaxid {
namespace {

using testing_util::NoiseFree;
using testing_util::SimulatedBalance;
using testing_util::TruthPsi;
using testing_util::TruthVehicle;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kAreaRatio = (0.02 * 0.02) / (0.17 * 0.17);

// The model of the noisy shipped-grid experiment with its map, and its data.
struct KfSetup {
  std::vector<BalanceData> data;
  LinearBalanceModel model;
  std::vector<WeightedBalanceData> weighted;
  LinearKfOptions options;
};

KfSetup MakeSetup(const Log& log) {
  KfSetup s;
  s.data = {MakeBalanceData(log)};
  const ThrustMap map = FitThrustMap(s.data, 1.0, kAreaRatio);
  s.model = {map.alpha, 0.10, kAreaRatio, map.table};
  s.weighted = {{&s.data[0], WithinHoldNoise(s.data[0]).Variances()}};
  s.options = KfOptionsFromConfig(testing_util::ReferenceVehicle().parameters, {});
  return s;
}

double MaxRelative(const ThetaVector& a, const ThetaVector& b) {
  return ((a - b).cwiseAbs().array() / b.cwiseAbs().array()).maxCoeff();
}

TEST(LinearBalanceModel, RegressorsReproduceTheNonlinearModel) {
  // Eq. 70 (with Z_bar + sigma alpha w1) against VehicleModel::Loads in the
  // balance setting (dynamics/vehicle_model.h, eqs. 57-63 and model.md
  // decision 5), written independently. The table holds the truth's
  // parametric sigma at the grid points, where the inputs sit.
  const Vehicle truth = TruthVehicle();
  const Eigen::VectorXd theta = truth.parameters.Values();
  SigmaTable table;
  table.omega1 = table.omega2 = {0, 110, 135, 160};
  for (double w1 : table.omega1) {
    for (double w2 : table.omega2) table.sigma.push_back(InterferenceLoss(0.12, w1, w2));
  }
  const LinearBalanceModel model{-5.9e-5, 0.10, kAreaRatio, table};
  const ThetaVector truth_theta = TruthPsi(truth).head<kNumTheta>();
  for (double w1 : table.omega1) {
    for (double w2 : table.omega2) {
      for (double dx : {-0.15, 0.0, 0.07}) {
        for (double dy : {-0.1, 0.0, 0.15}) {
          const InputVector u = {w1, w2, dx, dy};
          const LoadVector linear = model.Predict(u, truth_theta);
          const AeroLoads<double> a = truth.model.Loads(theta.data(), u.data(), Setting::kBalance,
                                                        static_cast<const double*>(nullptr));
          const double exact[6] = {a.force_B[0],  a.force_B[1],  a.force_B[2],
                                   a.moment_B[0], a.moment_B[1], a.moment_B[2]};
          for (int c = 0; c < kNumLoadChannels; ++c) {
            // The nonlinear model smooths the wake speed and the airspeed norm
            // (~1e-12 m/s, vehicle_model.h): with both rotors stopped its Z
            // is ~1e-10 N instead of 0; elsewhere the relative difference is
            // ~1e-14.
            EXPECT_NEAR(linear[c], exact[c], 1e-12 * std::fabs(exact[c]) + 1e-9)
                << LoadChannelName(c) << " at " << w1 << " " << w2 << " " << dx << " " << dy;
          }
        }
      }
    }
  }
}

TEST(LinearBalanceModel, SigmaWeightsInterpolateLikeTheTable) {
  SigmaTable table;
  table.omega1 = {0, 100, 150};
  table.omega2 = {0, 90, 120, 170};
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> sigma(0.85, 1.0), speed(-20, 200);
  for (int i = 0; i < 12; ++i) table.sigma.push_back(sigma(rng));
  for (int k = 0; k < 200; ++k) {
    const double w1 = speed(rng), w2 = speed(rng);  // inside and outside the grid
    const SigmaCellWeights w = SigmaWeights(table, w1, w2);
    double s = 0;
    for (int j = 0; j < 4; ++j) s += w.weight[j] * table.sigma[w.cell[j]];
    EXPECT_NEAR(s, InterferenceLossFromTable(table, w1, w2), 1e-15);
  }
}

TEST(LinearKf, EqualsBatchLeastSquaresWithTheSamePrior) {
  // Two routes to the same estimate: the recursion (covariance form, Joseph
  // update, one sample at a time) and blocked Householder QR of all whitened
  // rows with the same prior rows. With Q = 0 they are the same estimator in
  // exact arithmetic. Measured here: 1e-11 apart on the estimate, 4e-14 on P
  // (the filter's round-off grows with the diffuse prior, eps * P_0 * the
  // per-sample information on the first updates, and later updates shrink
  // it). Tolerances 1e-9 and 1e-10: a hundred times the round-off seen,
  // far below any statistical difference (the stds are ~1e-3 relative).
  BalanceScenario b;
  b.hold_s = 0.5;
  KfSetup s = MakeSetup(SimulatedBalance(b, 11));
  const LinearKfSummary kf = RunLinearKf(s.model, s.weighted, s.options);
  const BatchLeastSquaresSummary batch = SolveBatchLeastSquares(s.model, s.weighted, s.options);
  ASSERT_TRUE(kf.IsSolutionUsable()) << kf.message;
  ASSERT_TRUE(batch.usable) << batch.message;
  EXPECT_LT(MaxRelative(kf.estimate, batch.estimate), 1e-9);
  EXPECT_LT(MaxRelative(kf.covariance.diagonal(), batch.covariance.diagonal()), 1e-10);
  // P stays exactly symmetric (the Joseph update is symmetrised).
  EXPECT_EQ((kf.covariance - kf.covariance.transpose()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(kf.updates, s.data[0].NumRows());
  EXPECT_EQ(kf.history.t.size(), static_cast<size_t>(kf.updates));

  // The prior is diffuse: pure least squares (no prior rows) differs by the
  // prior's share of the information, (1/1e3)^2 / ~1e3 ~ 1e-9, times the
  // prior's distance from the estimate (up to ~7 scales for Cz_beta).
  LinearKfOptions no_prior = s.options;
  no_prior.prior_std = std::numeric_limits<double>::infinity();
  const BatchLeastSquaresSummary pure = SolveBatchLeastSquares(s.model, s.weighted, no_prior);
  ASSERT_TRUE(pure.usable) << pure.message;
  EXPECT_LT(MaxRelative(kf.estimate, pure.estimate), 1e-8);
}

TEST(LinearKf, NoiseFreeDataGiveTheTruth) {
  BalanceScenario b;
  b.hold_s = 0.1;
  KfSetup s = MakeSetup(SimulatedBalance(NoiseFree(b), 1));
  // Noise-free holds have no spread: R is floored at (1e-4 rms)^2; exact
  // data are fitted exactly whatever the weights.
  s.weighted[0].variance = WithinHoldNoise(s.data[0]).Variances();
  const LinearKfSummary kf = RunLinearKf(s.model, s.weighted, s.options);
  ASSERT_TRUE(kf.IsSolutionUsable()) << kf.message;
  const ThetaVector truth = TruthPsi(TruthVehicle()).head<kNumTheta>();
  // Cz_beta comes from Z_bar's combination beta - k Cz_beta: an error e in
  // Z_bar becomes e / k ~ 70 e in Cz_beta; the diffuse prior pulls by
  // ~1e-12 of the (floored) data's information. 1e-9 is near machine
  // precision after both.
  EXPECT_LT(MaxRelative(kf.estimate, truth), 1e-9);
}

TEST(LinearKf, MissingOutputsAreSkipped) {
  BalanceScenario b;
  b.hold_s = 0.5;
  Log log = SimulatedBalance(b, 5);
  // 10 % of Z, L, M and N missing at random, and some rows missing all four.
  std::mt19937_64 rng(9);
  std::bernoulli_distribution drop(0.1);
  const int rows = log.NumRows();
  for (const char* name : {"Z", "L", "M", "N"}) {
    std::vector<double>& column = log.values[log.ColumnIndex(name)];
    for (int k = 0; k < rows; ++k) {
      if (drop(rng) || k % 97 == 5) column[k] = kNaN;
    }
  }
  KfSetup s = MakeSetup(log);
  const LinearKfSummary kf = RunLinearKf(s.model, s.weighted, s.options);
  const BatchLeastSquaresSummary batch = SolveBatchLeastSquares(s.model, s.weighted, s.options);
  ASSERT_TRUE(kf.IsSolutionUsable()) << kf.message;
  EXPECT_GE(kf.skipped_rows, rows / 97);
  EXPECT_EQ(kf.updates + kf.skipped_rows, rows);
  // The batch route drops the same scalar outputs: same solution.
  EXPECT_LT(MaxRelative(kf.estimate, batch.estimate), 1e-8);
}

TEST(LinearKf, ProcessNoiseKeepsPOpen) {
  BalanceScenario b;
  b.hold_s = 0.5;
  KfSetup s = MakeSetup(SimulatedBalance(b, 2));
  const LinearKfSummary q0 = RunLinearKf(s.model, s.weighted, s.options);
  s.options.process_noise = 1e-6;
  const LinearKfSummary q = RunLinearKf(s.model, s.weighted, s.options);
  ASSERT_TRUE(q.IsSolutionUsable());
  // A random walk adds variance at every step: the final P is larger.
  EXPECT_GT(q.covariance.trace(), q0.covariance.trace());
  EXPECT_GT(q.history.trace_scaled.back(), q0.history.trace_scaled.back());
}

TEST(LinearKf, RejectsBadOptions) {
  BalanceScenario b;
  b.hold_s = 0.1;
  KfSetup s = MakeSetup(SimulatedBalance(b, 2));
  s.options.scale[2] = 0;
  const LinearKfSummary kf = RunLinearKf(s.model, s.weighted, s.options);
  EXPECT_FALSE(kf.IsSolutionUsable());
  EXPECT_NE(kf.message.find("Cz_beta"), std::string::npos) << kf.message;
}

}  // namespace
}  // namespace coaxid
