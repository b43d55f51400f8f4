// The RK4 stability test of the sensitivities' step (dynamics/rk4_stability.h)
// on random matrices scaled as badly as a vehicle's Jacobian (states in rad,
// m/s and rad/s; rows 1e-3 to 1e3 apart).
#include "dynamics/rk4_stability.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace coaxid {
namespace {

// A 14 x 14 (the vehicle with a stabilizer bar) D0 M D0^-1: M Gaussian,
// D0 log-uniform over 1e-3..1e3, so the eigenvalues are M's and the
// unscaled row sums are not.
Eigen::MatrixXd BadlyScaled(std::mt19937* rng) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> exponent(-3, 3);
  const int n = 14;
  Eigen::MatrixXd M(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) M(i, j) = normal(*rng);
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) d[i] = std::pow(10.0, exponent(*rng));
  return d.asDiagonal() * M * d.cwiseInverse().asDiagonal();
}

// Any positive scales give an upper bound (similarity keeps the
// eigenvalues): never below rho, to rounding.
TEST(Rk4Stability, EveryScaledRowSumBoundsTheSpectralRadius) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> exponent(-4, 4);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::MatrixXd A = BadlyScaled(&rng);
    const double rho = SpectralRadius(A);
    Eigen::VectorXd scales(A.rows());
    for (int i = 0; i < scales.size(); ++i) scales[i] = std::pow(10.0, exponent(rng));
    EXPECT_GE(ScaledGershgorinBound(A, Eigen::VectorXd()), rho * (1 - 1e-12));
    EXPECT_GE(ScaledGershgorinBound(A, scales), rho * (1 - 1e-12));
    EXPECT_GE(ScaledGershgorinBound(A, BalancingScales(A)), rho * (1 - 1e-12));
  }
}

// Balancing undoes the units: the unscaled row sums of these matrices run
// hundreds of times above rho; balanced, within the factor a Gaussian
// matrix's own row sums keep (about sqrt(n) = 3.7 at n = 14: its row sums
// grow as n, rho as sqrt(n)). Measured over the 200 trials: unscaled median
// ratio in the hundreds, balanced at most a few.
TEST(Rk4Stability, BalancingBringsTheBoundToTheSpectralRadius) {
  std::mt19937 rng(12);
  std::vector<double> unscaled, balanced;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::MatrixXd A = BadlyScaled(&rng);
    const double rho = SpectralRadius(A);
    unscaled.push_back(ScaledGershgorinBound(A, Eigen::VectorXd()) / rho);
    balanced.push_back(ScaledGershgorinBound(A, BalancingScales(A)) / rho);
  }
  std::sort(unscaled.begin(), unscaled.end());
  std::sort(balanced.begin(), balanced.end());
  EXPECT_GT(unscaled[100], 50);
  EXPECT_LT(balanced[100], 4);
  EXPECT_LT(balanced.back(), 8);
}

// The decision is h rho(A) <= limit, whatever the test balanced before (it
// keeps a balancing across calls): on matrices with h rho just on either
// side of the limit, in a random order.
TEST(Rk4Stability, TheDecisionIsTheSpectralRadiusWhateverCameBefore) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> side(0.9, 1.1);
  Rk4StabilityTest test(2.0);
  int stable = 0, unstable = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::MatrixXd A = BadlyScaled(&rng);
    const double h = 2.0 * side(rng) / SpectralRadius(A);
    const bool expected = h * SpectralRadius(A) <= 2.0;
    EXPECT_EQ(test.Stable(h, A), expected) << "trial " << trial;
    (expected ? stable : unstable) += 1;
  }
  EXPECT_GT(stable, 100);
  EXPECT_GT(unstable, 100);
  // Far inside the limit the row sums decide, once balanced.
  const long before = test.by_eigenvalues();
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::MatrixXd A = BadlyScaled(&rng);
    EXPECT_TRUE(test.Stable(0.05 / SpectralRadius(A), A));
  }
  EXPECT_EQ(test.by_eigenvalues(), before);
  // A non-finite Jacobian is never stable.
  Eigen::MatrixXd bad = Eigen::MatrixXd::Identity(3, 3);
  bad(1, 2) = NAN;
  EXPECT_FALSE(test.Stable(1e-3, bad));
}

}  // namespace
}  // namespace coaxid
