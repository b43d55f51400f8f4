// Flight logs averaged down to a fit rate (ident/fit_rate.h): the averaged
// rows are rows of the same vehicle, and a fit on them recovers the truth
// with the information of the rows they replace.
#include "ident/fit_rate.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "core/errors.h"
#include "dynamics/state.h"
#include "experiments/simulation/simulate_experiment.h"
#include "ident/output_error/output_error.h"
#include "tests/random_truth.h"
#include "tests/shipped_flight.h"

namespace coaxid {
namespace {

// A flight log of `rows` rows every `h` seconds from t = 1: random inputs,
// outputs p = 2 + 3 t, psi = `psi0` + 0.5 t (rad), q missing at `missing_row`.
EstimationLog Synthetic(int rows, double h, double psi0 = 0.1, int missing_row = -1) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> t(rows);
  std::vector<InputVector> inputs(rows);
  for (int k = 0; k < rows; ++k) {
    t[k] = 1 + h * k;
    for (double& v : inputs[k]) v = u(rng);
  }
  EstimationLog log;
  log.source = "synthetic.csv";
  log.name = "synthetic";
  log.kind = LogKind::kFlight;
  log.inputs = InputHold(t, inputs);
  log.inputs.SetLeadIn({0.5}, {InputVector{9, 9, 9, 9}});
  log.channels = {kP, kQ, kPsi};
  log.channel_names = {"p", "q", "psi"};
  log.values.resize(rows, 3);
  for (int k = 0; k < rows; ++k) {
    log.values(k, 0) = 2 + 3 * t[k];
    log.values(k, 1) = k == missing_row ? NAN : 0.0;
    log.values(k, 2) = std::remainder(psi0 + 0.5 * t[k], 2 * M_PI);
  }
  return log;
}

// The integral of a zero-order-hold input over [a, b).
double Impulse(const InputHold& hold, int input, double a, double b) {
  double sum = 0;
  for (int k = 0; k < hold.size(); ++k) {
    const double from = std::max(a, hold.time(k));
    const double to = std::min(b, k + 1 < hold.size() ? hold.time(k + 1) : INFINITY);
    if (to > from) sum += (to - from) * hold.input(k)[input];
  }
  return sum;
}

TEST(FitRate, RowsPerFitRowIsTheLargestRunWithinTheWindow) {
  EXPECT_EQ(RowsPerFitRow(Synthetic(400, 0.005), 100), 2);   // 200 Hz
  EXPECT_EQ(RowsPerFitRow(Synthetic(400, 0.001), 100), 10);  // 1 kHz
  EXPECT_EQ(RowsPerFitRow(Synthetic(400, 0.004), 100), 2);   // 250 Hz: 8 ms pairs
  std::string why;
  EXPECT_EQ(RowsPerFitRow(Synthetic(400, 0.005), 0, &why), 1);
  EXPECT_NE(why.find("own rate"), std::string::npos) << why;
  EXPECT_EQ(RowsPerFitRow(Synthetic(400, 1 / 150.0), 100, &why), 1);  // 150 Hz
  EXPECT_NE(why.find("below the fit rate"), std::string::npos) << why;
  EXPECT_EQ(RowsPerFitRow(Synthetic(400, 0.005, 0.1, 17), 100, &why), 1);
  EXPECT_NE(why.find("missing values"), std::string::npos) << why;
  EstimationLog uneven = Synthetic(400, 0.005);
  std::vector<double> t = uneven.inputs.times();
  std::vector<InputVector> u(t.size());
  for (size_t k = 200; k < t.size(); ++k) t[k] += 0.001;  // a 6 ms spacing at row 200
  uneven.inputs = InputHold(t, u);
  EXPECT_EQ(RowsPerFitRow(uneven, 100, &why), 1);
  EXPECT_NE(why.find("not evenly spaced (row 201)"), std::string::npos) << why;
  EstimationLog balance = Synthetic(400, 0.005);
  balance.kind = LogKind::kBalance;
  EXPECT_EQ(RowsPerFitRow(balance, 100, &why), 1);
}

TEST(FitRate, OutputsAreTheMeanAtTheMeanTimeAndAnglesStayOnTheCircle) {
  // psi crosses +-pi within the log: a run straddling the cut averages on
  // the circle, not to about 0.
  const EstimationLog log = Synthetic(603, 0.005, M_PI - 0.3);
  const EstimationLog a = AverageRows(log, 3);
  ASSERT_EQ(a.NumRows(), 201);
  EXPECT_EQ(a.LogRow(7), 21);  // messages name the log's rows
  for (int j = 0; j < a.NumRows(); ++j) {
    const double t = a.inputs.time(j);
    EXPECT_NEAR(t, 1 + 0.005 * (3 * j + 1), 1e-12);
    EXPECT_NEAR(a.values(j, 0), 2 + 3 * t, 1e-12);  // linear in t: the mean is exact
    EXPECT_NEAR(std::remainder(a.values(j, 2) - (M_PI - 0.3 + 0.5 * t), 2 * M_PI), 0, 1e-12)
        << "row " << j;
  }
}

TEST(FitRate, EachHoldAppliesTheImpulseOfTheLoggedInputs) {
  const EstimationLog log = Synthetic(400, 0.005);
  const EstimationLog a = AverageRows(log, 2);
  ASSERT_EQ(a.NumRows(), 200);
  for (int j = 0; j + 1 < a.NumRows(); ++j) {
    const double from = a.inputs.time(j), to = a.inputs.time(j + 1);
    for (int i = 0; i < kNumInputs; ++i) {
      EXPECT_NEAR(a.inputs.input(j)[i] * (to - from), Impulse(log.inputs, i, from, to), 1e-15)
          << "hold " << j << " input " << i;
    }
  }
  // The rows before the first averaged time join the source's lead-in.
  ASSERT_EQ(a.inputs.lead_in_times().size(), 2u);
  EXPECT_EQ(a.inputs.lead_in_times()[0], 0.5);
  EXPECT_EQ(a.inputs.lead_in_times()[1], log.inputs.time(0));
  EXPECT_EQ(a.inputs.lead_in_inputs()[1], log.inputs.input(0));
  EXPECT_THROW(AverageRows(Synthetic(5, 0.005), 3), InputError);
}

// What the averaging is for: on a closed-loop flight of a vehicle 10-30 % off
// the config, the fit of the averaged rows finds the truth, and with the
// precision of the fit of all rows, where keeping every other row loses half
// the information (std x sqrt(2)). The std of each ratio is the Cramer-Rao
// bound at the fit's own noise estimate, so a ratio of stds near 1 says the
// averaged pairs carry the information of the pairs.
TEST(FitRate, AFitOfAveragedPairsFindsTheTruthWithTheInformationOfThePairs) {
  const Vehicle nominal = ShippedVehicle();
  const FlightScenario s = ExcitedShippedFlight(8.0);
  OutputErrorOptions o;
  o.noise_relaxations = 1;
  for (uint64_t seed : {31, 32}) {
    const Vehicle truth = RandomTruth(nominal, seed);
    const EstimationLog log = MakeEstimationLog(SimulateFlight(truth, s, seed + 100));
    EstimationLog every_other = log;  // rows 0, 2, 4, ...
    {
      std::vector<double> t;
      std::vector<InputVector> u;
      for (int k = 0; k < log.NumRows(); k += 2) {
        t.push_back(log.inputs.time(k));
        // the pair's impulse over the longer hold, as AverageRows' inputs
        InputVector mean{};
        for (int i = 0; i < kNumInputs; ++i) {
          mean[i] =
              (log.inputs.input(k)[i] + log.inputs.input(std::min(k + 1, log.NumRows() - 1))[i]) /
              2;
        }
        u.push_back(mean);
      }
      every_other.inputs = InputHold(t, u);
      every_other.inputs.SetLeadIn(log.inputs.lead_in_times(), log.inputs.lead_in_inputs());
      every_other.values.resize(static_cast<int>(t.size()), log.NumChannels());
      for (int j = 0; j < every_other.values.rows(); ++j)
        every_other.values.row(j) = log.values.row(2 * j);
    }
    const OutputErrorResult all = FitOutputError(nominal, {log}, o);
    const OutputErrorResult averaged = FitOutputError(nominal, {AverageRows(log, 2)}, o);
    const OutputErrorResult dropped = FitOutputError(nominal, {every_other}, o);
    ASSERT_TRUE(all.usable && averaged.usable && dropped.usable);
    ASSERT_EQ(all.ratios.size(), averaged.ratios.size());
    double log_ratio_averaged = 0, log_ratio_dropped = 0;
    for (size_t k = 0; k < all.ratios.size(); ++k) {
      const ScaleFreeRatio& q = averaged.ratios[k];
      const double truth_value = q.Evaluate(truth.parameters);
      // 3 std: 12 checks, a false alarm in one has probability ~3 %.
      EXPECT_LT(std::fabs(q.value - truth_value), 3 * q.std)
          << "seed " << seed << " " << q.name << " = " << q.value << " +- " << q.std << ", truth "
          << truth_value << " (all rows: " << all.ratios[k].value << " +- " << all.ratios[k].std
          << ")";
      log_ratio_averaged += std::log(q.std / all.ratios[k].std) / all.ratios.size();
      log_ratio_dropped += std::log(dropped.ratios[k].std / all.ratios[k].std) / all.ratios.size();
    }
    // Geometric means of the std ratios: sqrt(2) = 1.41 is half the
    // information; 1.2 lies halfway between (log scale). Measured on seeds
    // 31-37: averaged 0.986-1.005, every other row 1.329-1.367.
    EXPECT_LT(std::exp(log_ratio_averaged), 1.2) << "seed " << seed;
    EXPECT_GT(std::exp(log_ratio_dropped), 1.2) << "seed " << seed;
  }
}

}  // namespace
}  // namespace coaxid
