// The candidate tests of ident/discover/linearised_fit.h on a linear regression whose
// answer is known: the score statistic against the closed form, and the
// cluster-robust test's level on autocorrelated residuals (where the
// white-noise test over-rejects) and its power.
#include "ident/discover/linearised_fit.h"

#include <cmath>
#include <random>

#include <Eigen/QR>
#include <gtest/gtest.h>

namespace coaxid {
namespace {

// AR(1) series: x_k = rho x_k-1 + sqrt(1 - rho^2) e_k (unit variance).
Eigen::VectorXd Ar1(int n, double rho, std::mt19937* rng) {
  std::normal_distribution<double> e(0, 1);
  Eigen::VectorXd x(n);
  x[0] = e(*rng);
  for (int k = 1; k < n; ++k) x[k] = rho * x[k - 1] + std::sqrt(1 - rho * rho) * e(*rng);
  return x;
}

// A linearised fit of y on [J0 | Z] at the least-squares fit of J0 alone
// (r = J0 b0 - y at the optimum, the costs' sign), clusters of `cluster` rows.
LinearisedFit Linearise(const Eigen::MatrixXd& J0, const Eigen::MatrixXd& Z,
                        const Eigen::VectorXd& y, int cluster) {
  Eigen::MatrixXd J(J0.rows(), J0.cols() + Z.cols());
  J << J0, Z;
  const Eigen::VectorXd b0 = J0.colPivHouseholderQr().solve(y);
  const Eigen::VectorXd r = J0 * b0 - y;
  LinearisedFit f;
  for (int c = 0; c < J.cols(); ++c) f.parameter_names.push_back("c" + std::to_string(c));
  f.parameter_scales = Eigen::VectorXd::Ones(J.cols());
  f.normal = J.transpose() * J;
  f.gradient = J.transpose() * r;
  for (int first = 0; first < J.rows(); first += cluster) {
    const int rows = std::min<int>(cluster, J.rows() - first);
    f.cluster_gradients.push_back(J.middleRows(first, rows).transpose() * r.segment(first, rows));
    f.cluster_residuals.push_back(rows);
    f.cluster_strata.push_back(0);
  }
  f.rss = r.squaredNorm();
  f.num_residuals = static_cast<int>(r.size());
  return f;
}

TEST(LinearisedFit, ScoreStepIsTheNestedLeastSquaresFit) {
  std::mt19937 rng(3);
  const int n = 600;
  Eigen::MatrixXd J0(n, 2), Z(n, 1);
  for (int k = 0; k < n; ++k) {
    J0(k, 0) = 1;
    J0(k, 1) = std::sin(0.01 * k);
    Z(k, 0) = std::cos(0.013 * k) + 0.3 * J0(k, 1);
  }
  std::normal_distribution<double> e(0, 0.1);
  Eigen::VectorXd y(n);
  for (int k = 0; k < n; ++k) y[k] = 2 - J0(k, 1) + 0.7 * Z(k, 0) + e(rng);
  const LinearisedFit f = Linearise(J0, Z, y, 20);
  const ColumnTest t = ColumnTester(f, {0, 1}).Test({2});
  ASSERT_TRUE(t.ok) << t.why_not;
  // Gauss-Newton from the nested optimum lands on the full least-squares fit.
  Eigen::MatrixXd J(n, 3);
  J << J0, Z;
  const Eigen::VectorXd full = J.colPivHouseholderQr().solve(y);
  EXPECT_NEAR(t.step[0], full[2], 1e-9);
  const Eigen::VectorXd r1 = J * full - y;
  EXPECT_NEAR(t.predicted_rss_drop, f.rss - r1.squaredNorm(), 1e-9 * f.rss);
  // The cluster-robust p is bounded by its nu - q + 1 = 29 degrees of freedom
  // (F(1, 29) > 23 for p < 1e-4), not by the 600 samples.
  EXPECT_LT(t.p_value, 1e-4);
}

TEST(LinearisedFit, ClusterRobustTestKeepsItsLevelOnAutocorrelatedResiduals) {
  // Smooth regressors and AR(1) noise with rho = 0.95 (correlation time 20
  // samples), clusters of 200 samples, nothing to find: the cluster-robust
  // p-value should fall below 0.05 in ~5 % of the runs; the white-noise one,
  // which counts 8000 samples as independent, far more often.
  std::mt19937 rng(4);
  const int n = 8000, runs = 200;
  int robust = 0, white = 0;
  for (int run = 0; run < runs; ++run) {
    Eigen::MatrixXd J0(n, 2), Z(n, 2);
    J0.col(0).setOnes();
    J0.col(1) = Ar1(n, 0.99, &rng);
    Z.col(0) = Ar1(n, 0.99, &rng);
    Z.col(1) = Ar1(n, 0.99, &rng);
    const Eigen::VectorXd y = 0.5 * J0.col(1) + Ar1(n, 0.95, &rng);
    const ColumnTest t = ColumnTester(Linearise(J0, Z, y, 200), {0, 1}).Test({2, 3});
    ASSERT_TRUE(t.ok) << t.why_not;
    robust += t.p_value < 0.05;
    white += t.white_p_value < 0.05;
  }
  // Binomial(200, 0.05): mean 10, std 3.1; [3, 20] is beyond 2.2 std either side.
  EXPECT_GE(robust, 3);
  EXPECT_LE(robust, 20);
  EXPECT_GT(white, 60);
}

TEST(LinearisedFit, ClusterRobustTestFindsARealRegressor) {
  std::mt19937 rng(5);
  const int n = 8000;
  Eigen::MatrixXd J0(n, 1), Z(n, 1);
  J0.col(0).setOnes();
  Z.col(0) = Ar1(n, 0.99, &rng);
  // The regressor carries 0.3 of the noise's std; over 40 clusters its score
  // is positive in nearly every one.
  const Eigen::VectorXd y = 0.3 * Z.col(0) + Ar1(n, 0.95, &rng);
  const ColumnTest t = ColumnTester(Linearise(J0, Z, y, 200), {0}).Test({1});
  ASSERT_TRUE(t.ok);
  EXPECT_LT(t.p_value, 1e-3);
  EXPECT_NEAR(t.step[0], 0.3, 0.1);
}

TEST(LinearisedFit, ColumnInTheNuisanceSpanIsNotTestable) {
  std::mt19937 rng(6);
  const int n = 400;
  Eigen::MatrixXd J0(n, 2), Z(n, 1);
  J0.col(0).setOnes();
  J0.col(1) = Ar1(n, 0.5, &rng);
  Z.col(0) = 2 * J0.col(1) - J0.col(0);
  const ColumnTest t = ColumnTester(Linearise(J0, Z, Ar1(n, 0, &rng), 20), {0, 1}).Test({2});
  EXPECT_FALSE(t.ok);
  EXPECT_NE(t.why_not.find("explained by the parameters already estimated"), std::string::npos);
}

// Issue 13's defect: a wind column nearly collinear with the declared ones
// gave wd = -48 m/s and a predicted RSS 3.2e6 below zero. A column the
// nuisance columns explain up to rounding (1e-9 of its size) must come out
// untestable, or with a drop in [0, RSS] and a step of sane size: never the
// absurd values the unguarded projection gives (measured without the
// guards: a step of 2.8e3 and a predicted drop of -4.4e-5).
TEST(LinearisedFit, NearlyCollinearColumnNeverGivesAbsurdValues) {
  std::mt19937 rng(7);
  const int n = 2000;
  Eigen::MatrixXd J0(n, 2), Z(n, 1);
  J0.col(0).setOnes();
  J0.col(1) = Ar1(n, 0.9, &rng);
  Z.col(0) = 2 * J0.col(1) - J0.col(0) + 1e-9 * Ar1(n, 0, &rng);
  const LinearisedFit f = Linearise(J0, Z, Ar1(n, 0.3, &rng), 50);
  const ColumnTest t = ColumnTester(f, {0, 1}).Test({2});
  if (t.ok) {
    EXPECT_GE(t.predicted_rss_drop, 0.0);
    EXPECT_LE(t.predicted_rss_drop, f.rss);
    EXPECT_LT(t.step.cwiseAbs().maxCoeff(), 1e3);
  } else {
    EXPECT_NE(t.why_not.find("not separable"), std::string::npos) << t.why_not;
  }
}

}  // namespace
}  // namespace coaxid
