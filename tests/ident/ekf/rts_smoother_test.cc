// The RTS smoother (ident/ekf/rts_smoother.h) against the closed-form answer: for
// a linear Gaussian model the smoothed means and covariances are the solution
// and inverse information of the batch least-squares problem over every state
// at once (prior, dynamics and measurement residuals, each whitened).
// Both are computed in double precision on a well-conditioned 2-state problem
// of 40 steps; they agree to round-off (1e-9 relative is generous).
#include "ident/ekf/rts_smoother.h"

#include <gtest/gtest.h>

#include <random>

#include <Eigen/Cholesky>
#include <Eigen/Dense>

namespace coaxid {
namespace {

TEST(EkfRtsSmootherTest, MatchesBatchLeastSquares) {
  const int n = 2, steps = 40;
  const double dt = 0.1;
  Eigen::Matrix2d Phi;
  Phi << 1, dt, 0, 1;  // constant velocity
  const Eigen::Matrix2d Q = (Eigen::Matrix2d() << 1e-3, 5e-4, 5e-4, 1e-2).finished();
  const double r = 0.05 * 0.05;  // position measured
  const Eigen::RowVector2d H(1, 0);
  const Eigen::Vector2d x0(0.3, -0.2);
  const Eigen::Matrix2d P0 = Eigen::Vector2d(0.5, 0.4).asDiagonal();

  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0, 1);
  std::vector<double> y(steps + 1);
  Eigen::Vector2d truth(0.1, 0.5);
  for (int k = 0; k <= steps; ++k) {
    if (k > 0) truth = Phi * truth + Eigen::Vector2d(0.03 * normal(rng), 0.1 * normal(rng));
    y[k] = truth[0] + std::sqrt(r) * normal(rng);
  }

  // Filter (update at every step, including k = 0) and smoother.
  RtsSmoother smoother(n);
  Eigen::VectorXd x = x0;
  Eigen::MatrixXd P = P0;
  std::string error;
  auto update = [&](int k) {
    const double s = (H * P * H.transpose())(0, 0) + r;
    const Eigen::Vector2d K = P * H.transpose() / s;
    x += K * (y[k] - (H * x)(0, 0));
    const Eigen::Matrix2d IKH = Eigen::Matrix2d::Identity() - K * H;
    P = IKH * P * IKH.transpose() + K * r * K.transpose();
  };
  update(0);
  for (int k = 1; k <= steps; ++k) {
    const Eigen::VectorXd x_pred = Phi * x;
    const Eigen::MatrixXd P_pred = Phi * P * Phi.transpose() + Q;
    ASSERT_TRUE(smoother.AddTransition(x, P, Phi, x_pred, P_pred, &error)) << error;
    x = x_pred;
    P = P_pred;
    update(k);
  }
  std::vector<Eigen::VectorXd> xs(steps + 1);
  std::vector<Eigen::MatrixXd> Ps(steps + 1);
  smoother.Smooth(x, P, [&](int k, const Eigen::VectorXd& m, const Eigen::MatrixXd& C) {
    xs[k] = m;
    Ps[k] = C;
  });

  // Batch: information matrix and vector over z = [x_0; ...; x_N].
  const int dim = n * (steps + 1);
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(dim, dim);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(dim);
  const Eigen::Matrix2d P0i = P0.inverse(), Qi = Q.inverse();  // 2 x 2, test only
  info.block(0, 0, n, n) += P0i;
  b.segment(0, n) += P0i * x0;
  for (int k = 0; k <= steps; ++k) {
    info.block(n * k, n * k, n, n) += H.transpose() * H / r;
    b.segment(n * k, n) += H.transpose() * y[k] / r;
    if (k < steps) {
      // r_k = x_{k+1} - Phi x_k, weight Q^-1.
      Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, dim);
      J.block(0, n * k, n, n) = -Phi;
      J.block(0, n * (k + 1), n, n) = Eigen::Matrix2d::Identity();
      info += J.transpose() * Qi * J;
    }
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(info);
  ASSERT_EQ(llt.info(), Eigen::Success);
  const Eigen::VectorXd z = llt.solve(b);
  const Eigen::MatrixXd C = llt.solve(Eigen::MatrixXd::Identity(dim, dim));
  for (int k = 0; k <= steps; ++k) {
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(xs[k][i], z[n * k + i], 1e-9) << "step " << k;
      for (int j = 0; j < n; ++j) {
        EXPECT_NEAR(Ps[k](i, j), C(n * k + i, n * k + j), 1e-9 * C.diagonal().maxCoeff())
            << "step " << k;
      }
    }
  }
}

TEST(EkfRtsSmootherTest, RejectsASingularPrediction) {
  RtsSmoother smoother(2);
  std::string error;
  const Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(2, 2);
  EXPECT_FALSE(smoother.AddTransition(Eigen::VectorXd::Zero(2), zero, zero,
                                      Eigen::VectorXd::Zero(2), zero, &error));
  EXPECT_FALSE(error.empty());
}

}  // namespace
}  // namespace coaxid
