// A refinement step (SteppedParameters, ident/ekf/refinement.h): a product of
// sign-keeping parameters stays put along a step that leaves it unchanged
// to first order (the ridge k_b d_u), where the straight step leaves it; a
// parameter whose bounds allow either sign steps straight; and the result
// lies within the bounds for random steps and bounds.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "ident/ekf/refinement.h"

namespace coaxid {
namespace {

TEST(RefinementStep, FollowsAProductRidgeInLogs) {
  // k_b 0.13, d_u 0.34 (the GLMAV bar's pass 1, seed 8101): a step that
  // keeps k_b d_u to first order, dk / k = -dd / d = 1.4.
  const Eigen::Vector2d p(0.13, 0.34), step(0.13 * 1.4, -0.34 * 1.4);
  const Eigen::Vector2d lower(0.0, 0.0), upper(2.0, 0.5);
  const Eigen::VectorXd to = SteppedParameters(p, step, 1.0, lower, upper);
  EXPECT_NEAR(to[0] * to[1], p[0] * p[1], 1e-12);
  EXPECT_NEAR(to[0], 0.13 * std::exp(1.4), 1e-12);
  const Eigen::Vector2d straight = (p + step).cwiseMax(lower).cwiseMin(upper);
  EXPECT_EQ(straight[1], 0.0);  // the straight step: d_u at its bound, off the ridge
  // Bounds that allow either sign: the straight step.
  const Eigen::Vector2d q(0.1, -0.2), q_step(0.3, 0.05), wide(-1, -1), wide_upper(1, 1);
  const Eigen::VectorXd mixed = SteppedParameters(q, q_step, 0.5, wide, wide_upper);
  EXPECT_DOUBLE_EQ(mixed[0], 0.1 + 0.15);
  EXPECT_DOUBLE_EQ(mixed[1], -0.2 + 0.025);
}

TEST(RefinementStep, EndsWithinTheBoundsOnRandomSteps) {
  std::mt19937_64 rng(4242);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + trial % 6;
    Eigen::VectorXd lower(n), upper(n), p(n), step(n);
    for (int k = 0; k < n; ++k) {
      lower[k] = uniform(rng) < 0.5 ? 0.0 : -uniform(rng);
      upper[k] = 0.1 + uniform(rng);
      p[k] = lower[k] + (upper[k] - lower[k]) * uniform(rng);
      step[k] = 3 * normal(rng);
    }
    const Eigen::VectorXd to = SteppedParameters(p, step, 1.0, lower, upper);
    ASSERT_TRUE(to.allFinite()) << "trial " << trial;
    for (int k = 0; k < n; ++k) {
      EXPECT_GE(to[k], lower[k]) << "trial " << trial;
      EXPECT_LE(to[k], upper[k]) << "trial " << trial;
    }
  }
}

}  // namespace
}  // namespace coaxid
