// The candidate tests of ident/discover/linearised_fit.h on a linear regression whose
// answer is known: the score statistic against the closed form, and the
// cluster-robust test's level on autocorrelated residuals (where the
// white-noise test over-rejects) and its power.
#include "ident/discover/linearised_fit.h"

#include <cmath>
#include <random>
#include <string>
#include <vector>

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
  std::vector<std::string> names;
  std::vector<int> columns;
  for (int c = 0; c < J.cols(); ++c) {
    names.push_back("c" + std::to_string(c));
    columns.push_back(c);
  }
  LinearisedFit f(0, kNumStates, names, Eigen::VectorXd::Ones(J.cols()));
  f.AddNormal(columns, J.transpose() * J);
  for (int first = 0; first < J.rows(); first += cluster) {
    const int rows = std::min<int>(cluster, J.rows() - first);
    f.AddCluster(columns, J.middleRows(first, rows).transpose() * r.segment(first, rows), 0);
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

// A column that only a short block of rows separates from the nuisance
// columns, as a balance log separates wake_interference beside a long flight:
// its squared sine against them is about 1e-7 (a fixed floor of 1e-6 called
// it not separable), far above what rounding leaves of it. Its score test
// must find it (the 20 clusters of the separating rows carry its score:
// T^2 about 20) and its step must be its coefficient, within 5 times the
// 0.016 std its separated part gives with this noise.
TEST(LinearisedFit, ColumnSeparatedByAFewRowsIsTestable) {
  std::mt19937 rng(9);
  std::normal_distribution<double> e(0, 1);
  const int n = 8000, separated = 1000;
  Eigen::MatrixXd J0(n, 2), Z(n, 1);
  J0.col(0).setOnes();
  J0.col(1) = Ar1(n, 0.9, &rng);
  Z.col(0) = 2 * J0.col(1) - J0.col(0);
  for (int k = n - separated; k < n; ++k) Z(k, 0) += 2e-3 * e(rng);
  Eigen::VectorXd y = 1.0 * Z.col(0);
  for (int k = 0; k < n; ++k) y[k] += 1e-3 * e(rng);
  const LinearisedFit f = Linearise(J0, Z, y, 50);
  const ColumnTester tester(f, {0, 1});
  const ColumnTest t = tester.Test({2});
  ASSERT_TRUE(t.ok) << t.why_not;
  EXPECT_LT(t.p_value, 1e-3);
  EXPECT_NEAR(t.step[0], 1.0, 0.08);
  EXPECT_GE(t.predicted_rss_drop, 0.0);
  EXPECT_LE(t.predicted_rss_drop, f.rss);
}

// A multiple-shooting problem shaped like the output-error one: two logs of
// segments, each segment's rows depending on its own start state and the
// parameters, a continuity tie coupling it to the next segment of its log,
// one state column no row holds. The block-tridiagonal elimination must give
// what the projection on the dense Jacobian gives (QR, no normal matrix):
// the step, the predicted drop and the cluster-robust statistic.
TEST(LinearisedFit, BlockEliminationEqualsTheDenseProjection) {
  std::mt19937 rng(8);
  std::normal_distribution<double> e(0, 1);
  const std::vector<int> segments_per_log = {4, 3};
  const int P = 5, rows_per_segment = 90, cluster_rows = 30;
  const int segments = 7, S = kNumStates * segments;
  const int ties = kNumStates * (segments - static_cast<int>(segments_per_log.size()));
  const int R = segments * rows_per_segment + ties;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(R, S + P);
  struct Block {
    std::vector<int> rows, columns;
    std::vector<int> cluster_ends;  // local row ends
    int stratum;
  };
  std::vector<Block> blocks;
  int row = 0, segment = 0;
  for (int log = 0; log < static_cast<int>(segments_per_log.size()); ++log) {
    for (int j = 0; j < segments_per_log[log]; ++j, ++segment) {
      const bool has_next = j + 1 < segments_per_log[log];
      Block b;
      b.stratum = log;
      for (int k = 0; k < kNumStates; ++k) b.columns.push_back(kNumStates * segment + k);
      for (int k = 0; k < P; ++k) b.columns.push_back(S + k);
      if (has_next) {
        for (int k = 0; k < kNumStates; ++k) b.columns.push_back(kNumStates * (segment + 1) + k);
      }
      for (int k = 0; k < rows_per_segment; ++k, ++row) {
        b.rows.push_back(row);
        for (int c = 0; c < kNumStates + P; ++c) J(row, b.columns[c]) = e(rng);
        if ((k + 1) % cluster_rows == 0 && k + 1 < rows_per_segment) b.cluster_ends.push_back(k + 1);
      }
      for (int k = 0; has_next && k < kNumStates; ++k, ++row) {
        b.rows.push_back(row);
        for (int c = 0; c < kNumStates + P; ++c) J(row, b.columns[c]) = 0.3 * e(rng);
        J(row, kNumStates * (segment + 1) + k) = -1;  // the next segment's start
      }
      b.cluster_ends.push_back(static_cast<int>(b.rows.size()));
      blocks.push_back(b);
    }
  }
  ASSERT_EQ(row, R);
  for (int j = 0; j < segments; ++j) J.col(kNumStates * j + 3).setZero();  // a state no row holds
  const std::vector<int> nuisance = {0, 1, 2}, tested = {3, 4};
  Eigen::MatrixXd J0(R, S + 3), Z(R, 2);
  J0 << J.leftCols(S + 3);
  Z << J.rightCols(2);
  Eigen::VectorXd y(R);
  for (int k = 0; k < R; ++k) y[k] = 0.2 * Z(k, 0) + e(rng);
  const Eigen::VectorXd r = J0 * J0.colPivHouseholderQr().solve(y) - y;

  LinearisedFit f(segments, kNumStates, {"a", "b", "c", "d", "e"}, Eigen::VectorXd::Ones(P));
  std::vector<Eigen::VectorXd> cluster_scores;  // reference: Z~_c^T r_c
  const Eigen::MatrixXd Zt = Z - J0 * J0.colPivHouseholderQr().solve(Z);
  for (const Block& b : blocks) {
    Eigen::MatrixXd Jb(b.rows.size(), b.columns.size());
    Eigen::VectorXd rb(b.rows.size());
    Eigen::MatrixXd Ztb(b.rows.size(), 2);
    for (size_t a = 0; a < b.rows.size(); ++a) {
      for (size_t c = 0; c < b.columns.size(); ++c) Jb(a, c) = J(b.rows[a], b.columns[c]);
      rb[a] = r[b.rows[a]];
      Ztb.row(a) = Zt.row(b.rows[a]);
    }
    f.AddNormal(b.columns, Jb.transpose() * Jb);
    int begin = 0;
    for (int end : b.cluster_ends) {
      f.AddCluster(b.columns,
                   Jb.middleRows(begin, end - begin).transpose() * rb.segment(begin, end - begin),
                   b.stratum);
      cluster_scores.push_back(Ztb.middleRows(begin, end - begin).transpose() *
                               rb.segment(begin, end - begin));
      begin = end;
    }
  }
  f.rss = r.squaredNorm();
  f.num_residuals = R;
  ASSERT_EQ(f.NumColumns(), S + P);

  // Reference: S = Z~^T Z~, G = Z~^T r, C from the cluster scores centred per log.
  const Eigen::MatrixXd S_ref = Zt.transpose() * Zt;
  const Eigen::VectorXd G = Zt.transpose() * r;
  const Eigen::VectorXd step = -S_ref.ldlt().solve(G);
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(2, 2);
  double nu = 0;
  for (int log = 0; log < 2; ++log) {
    std::vector<Eigen::VectorXd> members;
    for (size_t m = 0; m < f.clusters.size(); ++m) {
      if (f.clusters[m].stratum == log) members.push_back(cluster_scores[m]);
    }
    const int Ml = static_cast<int>(members.size());
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(2);
    for (const Eigen::VectorXd& g : members) mean += g / Ml;
    for (const Eigen::VectorXd& g : members) {
      C += double(Ml) / (Ml - 1) * (g - mean) * (g - mean).transpose();
    }
    nu += Ml - 1;
  }
  const double F = G.dot(C.ldlt().solve(G)) * (nu - 2 + 1) / (2 * nu);

  const ColumnTest t = ColumnTester(f, nuisance).Test(tested);
  ASSERT_TRUE(t.ok) << t.why_not;
  // Both sides are exact up to rounding and the elimination's 1e-10 ridge.
  for (int c = 0; c < 2; ++c) EXPECT_NEAR(t.step[c], step[c], 1e-7 * step.norm());
  EXPECT_NEAR(t.predicted_rss_drop, G.dot(-step), 1e-7 * G.dot(-step));
  EXPECT_NEAR(t.statistic, F, 1e-7 * F);
  EXPECT_EQ(t.covariance_dof, nu);
  EXPECT_EQ(t.clusters, static_cast<int>(cluster_scores.size()));
  EXPECT_GT(F, 1.0);  // the tested columns carry y: the comparison is not of zeros
}

}  // namespace
}  // namespace coaxid
