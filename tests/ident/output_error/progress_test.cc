// The time-left estimate of the output-error progress lines.
#include "ident/output_error/progress.h"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace coaxid
