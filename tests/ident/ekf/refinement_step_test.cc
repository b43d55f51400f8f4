// The two shapes of a refinement step (ident/ekf/refinement_step.h):
//  - logarithmic: a product of sign-keeping parameters stays put along a
//    step that leaves it unchanged to first order (the ridge k_b d_u), where
//    the straight step changes it;
//  - linear: inside the bounds the straight step itself; a parameter that
//    would cross a bound is held there and the others land on the
//    conditional mean of N(p + step, P), checked against the 2 x 2 formula
//    x2 + P21 / P11 (b1 - x1);
//  - both within the bounds for random steps, covariances and bounds.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "ident/ekf/refinement_step.h"

namespace coaxid {
namespace {

TEST(RefinementStep, ALogarithmicStepFollowsAProductRidge) {
  // k_b 0.13, d_u 0.34 (the GLMAV bar's pass 1, seed 8101): a step that
  // keeps k_b d_u to first order, dk / k = -dd / d = 1.4.
  const Eigen::Vector2d p(0.13, 0.34), step(0.13 * 1.4, -0.34 * 1.4);
  const Eigen::Vector2d lower(0.0, 0.0), upper(2.0, 0.5);
  const Eigen::Matrix2d P = Eigen::Matrix2d::Identity();
  const Eigen::VectorXd log_step =
      SteppedParameters(p, step, 1.0, RefinementStepShape::kLogarithmic, P, lower, upper);
  EXPECT_NEAR(log_step[0] * log_step[1], p[0] * p[1], 1e-12);
  EXPECT_NEAR(log_step[0], 0.13 * std::exp(1.4), 1e-12);
  const Eigen::VectorXd straight =
      SteppedParameters(p, step, 1.0, RefinementStepShape::kLinear, P, lower, upper);
  EXPECT_LT(straight[0] * straight[1], 0.5 * p[0] * p[1]);  // d_u at its bound 0: off the ridge
  // A parameter whose bounds allow either sign steps straight in both shapes.
  const Eigen::Vector2d q(0.1, -0.2), q_step(0.3, 0.05);
  const Eigen::Vector2d wide(-1, -1), wide_upper(1, 1);
  const Eigen::VectorXd mixed =
      SteppedParameters(q, q_step, 0.5, RefinementStepShape::kLogarithmic, P, wide, wide_upper);
  EXPECT_DOUBLE_EQ(mixed[0], 0.1 + 0.15);
  EXPECT_DOUBLE_EQ(mixed[1], -0.2 + 0.025);
}

TEST(RefinementStep, ALinearStepHeldAtABoundMovesTheOthersOnTheirConditionalMean) {
  Eigen::Matrix2d P;
  P << 4.0, -3.0, -3.0, 9.0;
  const Eigen::Vector2d p(0.02, 1.0), step(-0.05, 0.3);
  const Eigen::Vector2d lower(0.0, -10.0), upper(0.2, 10.0);
  // Inside the bounds: the straight step.
  const Eigen::VectorXd inside =
      SteppedParameters(p, step, 0.2, RefinementStepShape::kLinear, P, lower, upper);
  EXPECT_DOUBLE_EQ(inside[0], 0.02 - 0.01);
  EXPECT_DOUBLE_EQ(inside[1], 1.0 + 0.06);
  // The whole step takes the first below 0: held at 0, the second at
  // 1.3 + (-3 / 4) (0 - (-0.03)) = 1.2775.
  const Eigen::VectorXd held =
      SteppedParameters(p, step, 1.0, RefinementStepShape::kLinear, P, lower, upper);
  EXPECT_DOUBLE_EQ(held[0], 0.0);
  EXPECT_NEAR(held[1], 1.3 - 0.75 * 0.03, 1e-14);
}

TEST(RefinementStep, BothShapesEndWithinTheBoundsOnRandomSteps) {
  std::mt19937_64 rng(4242);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + trial % 6;
    Eigen::MatrixXd A(n, n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) A(i, j) = normal(rng);
    }
    const Eigen::MatrixXd P = A * A.transpose() + 1e-3 * Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd lower(n), upper(n), p(n), step(n);
    for (int k = 0; k < n; ++k) {
      lower[k] = uniform(rng) < 0.5 ? 0.0 : -uniform(rng);
      upper[k] = 0.1 + uniform(rng);
      p[k] = lower[k] + (upper[k] - lower[k]) * uniform(rng);
      step[k] = 3 * normal(rng);
    }
    for (const RefinementStepShape shape :
         {RefinementStepShape::kLogarithmic, RefinementStepShape::kLinear}) {
      const Eigen::VectorXd to = SteppedParameters(p, step, 1.0, shape, P, lower, upper);
      ASSERT_TRUE(to.allFinite()) << "trial " << trial;
      for (int k = 0; k < n; ++k) {
        EXPECT_GE(to[k], lower[k]) << "trial " << trial;
        EXPECT_LE(to[k], upper[k]) << "trial " << trial;
      }
    }
  }
}

}  // namespace
}  // namespace coaxid
