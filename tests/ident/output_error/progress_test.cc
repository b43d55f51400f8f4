// The time-left estimate of the output-error progress lines.
#include "ident/output_error/progress.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <string>

namespace coaxid {
namespace {

TEST(IterationsLeftAtLinearRate, CountsTheDropsAboveTheStop) {
  // Drops 100 then 10 (rho = 0.1); the stop is a drop below 1e-7 x 1e6 = 0.1:
  // the next drops 1, 0.1 (not below), 0.01 -> 3 more iterations.
  EXPECT_EQ(IterationsLeftAtLinearRate(100, 10, 1e6, 1e-7), 3);
  // The rule it stands for, checked by iterating the rate.
  for (const double rho : {0.05, 0.3, 0.7, 0.95}) {
    double drop = 50, cost = 2e5;
    const int predicted = IterationsLeftAtLinearRate(drop / rho, drop, cost, 1e-9);
    int counted = 0;
    while (!(drop < 1e-9 * cost)) {
      drop *= rho;
      ++counted;
    }
    EXPECT_NEAR(predicted, counted, 1) << rho;  // the ceil of a logarithm against a count
  }
  EXPECT_EQ(IterationsLeftAtLinearRate(10, 0.05, 1e6, 1e-7), 0);  // already below the stop
  EXPECT_EQ(IterationsLeftAtLinearRate(0, 10, 1e6, 1e-7), -1);    // no previous drop
  EXPECT_EQ(IterationsLeftAtLinearRate(10, 20, 1e6, 1e-7), -1);   // not converging
  EXPECT_EQ(IterationsLeftAtLinearRate(10, -1, 1e6, 1e-7), -1);   // a rejected step
}

TEST(OutputErrorProgress, PrintsTheTrustRegionBesideTheCost) {
  std::string line;
  OutputErrorProgress progress([&line](const std::string& l) { line = l; }, "stage 1/1",
                               std::chrono::steady_clock::now(), 12000, 1e-6);
  ceres::IterationSummary s;
  s.iteration = 3;
  s.cost = 85183.94;
  s.step_norm = 0.0894;
  s.trust_region_radius = 6.4e4;
  s.relative_decrease = 0.393;
  s.step_is_successful = true;
  EXPECT_EQ(progress(s), ceres::SOLVER_CONTINUE);
  EXPECT_NE(line.find("stage 1/1: iteration  3  cost 8.518394e+04  |step| 8.94e-02"),
            std::string::npos)
      << line;
  EXPECT_NE(line.find("tr_radius 6.4e+04  tr_ratio 0.39"), std::string::npos) << line;
}

// Ceres reports a trial point the model failed at with the largest double as
// its cost and -1.8e308 as its ratio: printed as numbers the line ran past
// its buffer and lost the elapsed time.
TEST(OutputErrorProgress, SaysWhenTheModelFailedAtTheTrialPoint) {
  std::string line;
  OutputErrorProgress progress([&line](const std::string& l) { line = l; }, "stage 2/2",
                               std::chrono::steady_clock::now(), 12000, 1e-6);
  ceres::IterationSummary s;
  s.iteration = 4;
  s.cost = std::numeric_limits<double>::max();
  s.step_norm = 12.9;
  s.trust_region_radius = 3.9;
  s.relative_decrease = -std::numeric_limits<double>::max();
  s.step_is_successful = false;
  EXPECT_EQ(progress(s), ceres::SOLVER_CONTINUE);
  EXPECT_NE(line.find("iteration  4  the model failed at the trial point  |step| 1.29e+01"),
            std::string::npos)
      << line;
  EXPECT_NE(line.find("tr_ratio -inf  elapsed "), std::string::npos) << line;
  EXPECT_LT(line.size(), 200u) << line;
}

}  // namespace
}  // namespace coaxid
