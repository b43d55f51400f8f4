// The compressed segment block gives Ceres the full block's cost, gradient
// and normal equations (J^T J, J^T r); the output-error tests fit through it.
#include "ident/output_error/compressed_segment_cost.h"

#include <cmath>
#include <memory>
#include <random>
#include <thread>

#include <Eigen/QR>
#include <gtest/gtest.h>

#include "experiments/simulation/simulate_experiment.h"
#include "ident/free_parameters.h"
#include "ident/output_error/output_error.h"

namespace coaxid {
namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Block {
  Eigen::VectorXd r;
  Eigen::MatrixXd J;  // [s_j | theta | s_j+1]
};

Block EvaluateBlock(const ceres::CostFunction& cost, const double* const* parameters, int P) {
  const int m = cost.num_residuals();
  RowMajor J_s(m, kNumStates), J_t(m, P), J_n(m, kNumStates);
  Block b;
  b.r.resize(m);
  double* jacobians[] = {J_s.data(), J_t.data(), J_n.data()};
  EXPECT_TRUE(cost.Evaluate(parameters, b.r.data(), jacobians));
  b.J.resize(m, 2 * kNumStates + P);
  b.J << J_s, J_t, J_n;
  return b;
}

// A 1 s segment (rows 20-220) of a simulated 1.5 s flight of the config
// vehicle, every channel weighted by 0.01.
struct OneSegment {
  explicit OneSegment(uint64_t seed)
      : vehicle(LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml")),
        free(vehicle.parameters),
        log(MakeEstimationLog(SimulateFlight(vehicle, Scenario(), seed))),
        channel_std(log.NumChannels(), 0.01) {}
  static FlightScenario Scenario() {
    FlightScenario scenario;
    scenario.duration_s = 1.5;
    scenario.excitation.start_s = 0.0;
    return scenario;
  }
  std::unique_ptr<FlightSegmentCost> Cost() const {
    return std::make_unique<FlightSegmentCost>(vehicle.model, free, log, first, last, true,
                                               channel_std, 1e-2,
                                               OutputErrorOptions::DefaultIntegrator());
  }
  const Vehicle vehicle;
  const FreeParameters free;
  const EstimationLog log;
  const std::vector<double> channel_std;
  const int first = 20, last = 220;
};

TEST(CompressedSegmentCost, GivesTheFullBlocksNormalEquationsAndCost) {
  const OneSegment one(7);
  const EstimationLog& log = one.log;
  const int first = one.first, last = one.last, P = one.free.size();
  const FreeParameters& free = one.free;
  const auto full = one.Cost();
  const CompressedSegmentCost compressed(one.Cost());
  ASSERT_TRUE(compressed.compressed());
  EXPECT_EQ(compressed.num_residuals(), kNumStates + P + 1 + kNumStates);
  ASSERT_GT(full->num_residuals(), 20 * compressed.num_residuals());

  // Off the simulated truth, so that the residuals are not noise alone.
  Eigen::VectorXd s0 = InitialStateFromLog(log, first), s1 = InitialStateFromLog(log, last);
  s0[kW] += 0.05;
  Eigen::VectorXd theta = free.ScaledValues();
  theta *= 1.05;
  const double* parameters[] = {s0.data(), theta.data(), s1.data()};
  const Block a = EvaluateBlock(*full, parameters, P);
  const Block b = EvaluateBlock(compressed, parameters, P);
  const Eigen::MatrixXd H = a.J.transpose() * a.J, H_c = b.J.transpose() * b.J;
  const Eigen::VectorXd g = a.J.transpose() * a.r, g_c = b.J.transpose() * b.r;
  // Sums of 3000 products against an orthogonal transformation of them:
  // agreement to round-off relative to the largest entry.
  EXPECT_LT((H - H_c).cwiseAbs().maxCoeff(), 1e-10 * H.cwiseAbs().maxCoeff());
  EXPECT_LT((g - g_c).cwiseAbs().maxCoeff(), 1e-10 * g.cwiseAbs().maxCoeff());
  EXPECT_NEAR(b.r.squaredNorm(), a.r.squaredNorm(), 1e-12 * a.r.squaredNorm());

  // Cost alone (a trial point): same norm, at the kept point and elsewhere.
  Eigen::VectorXd r(compressed.num_residuals()), r_full(full->num_residuals());
  ASSERT_TRUE(compressed.Evaluate(parameters, r.data(), nullptr));
  EXPECT_NEAR(r.squaredNorm(), a.r.squaredNorm(), 1e-12 * a.r.squaredNorm());
  theta[0] *= 1.01;
  ASSERT_TRUE(compressed.Evaluate(parameters, r.data(), nullptr));
  ASSERT_TRUE(full->Evaluate(parameters, r_full.data(), nullptr));
  EXPECT_NEAR(r.squaredNorm(), r_full.squaredNorm(), 1e-12 * r_full.squaredNorm());
}

// Standard normal entries.
Eigen::MatrixXd Gaussian(int rows, int cols, std::mt19937* rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(rows, cols);
  for (int j = 0; j < cols; ++j) {
    for (int i = 0; i < rows; ++i) A(i, j) = normal(*rng);
  }
  return A;
}

// The compression itself (CompressRows), on a segment's shape (3000 rows,
// 24 columns) with columns scaled over six decades as a fit's are: by
// Cholesky, the Householder QR's R^T R, A^T r and |r| to round-off, and the
// same |Q1^T r| entries and |Q2^T r| as the QR (R's rows differ only by
// sign).
TEST(CompressRows, ByCholeskyGivesTheHouseholderQrsBlock) {
  std::mt19937 rng(11);
  const int m = 3000, n = 24;
  Eigen::MatrixXd A = Gaussian(m, n, &rng);
  for (int j = 0; j < n; ++j) A.col(j) *= std::pow(10.0, -3.0 + 6.0 * j / (n - 1));
  Eigen::VectorXd r = Gaussian(m, 1, &rng);
  r += A * Eigen::VectorXd::Constant(n, 0.3);  // half explained by the columns
  const CompressedRows c = CompressRows(A, r);
  ASSERT_TRUE(c.by_cholesky);
  const Eigen::MatrixXd H = A.transpose() * A, H_c = c.R.transpose() * c.R;
  const Eigen::VectorXd g = A.transpose() * r, g_c = c.R.transpose() * c.head;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {  // relative to the entry's own scale
      EXPECT_NEAR(H_c(i, j), H(i, j), 1e-12 * std::sqrt(H(i, i) * H(j, j))) << i << ", " << j;
    }
    EXPECT_NEAR(g_c[i], g[i], 1e-12 * std::sqrt(H(i, i)) * r.norm()) << i;
  }
  EXPECT_NEAR(c.head.squaredNorm() + c.rest * c.rest, r.squaredNorm(), 1e-12 * r.squaredNorm());
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::VectorXd qtr = qr.householderQ().adjoint() * r;
  EXPECT_NEAR(c.rest, qtr.tail(m - n).norm(), 1e-10 * r.norm());
  for (int i = 0; i < n; ++i) EXPECT_NEAR(std::abs(c.head[i]), std::abs(qtr[i]), 1e-9 * r.norm());
}

// A column with no effect on the outputs (a parameter its segment does not
// see) or one the others give exactly: a zero row of R, nothing of r along
// it. Residuals the columns explain exactly (noise-free, |Q2^T r| = 0),
// where |r|^2 - |Q1^T r|^2 would be round-off: by Householder QR.
TEST(CompressRows, DependentColumnsAndResidualsExplainedExactly) {
  std::mt19937 rng(12);
  const int m = 400, n = 10;
  const Eigen::MatrixXd A = Gaussian(m, n, &rng);
  const Eigen::VectorXd r = Gaussian(m, 1, &rng);

  Eigen::MatrixXd dependent = A;
  dependent.col(4).setZero();
  dependent.col(7) = 2.0 * dependent.col(1) - dependent.col(3);
  const CompressedRows a = CompressRows(dependent, r);
  EXPECT_TRUE(a.by_cholesky);
  EXPECT_EQ(a.R.row(4).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT(a.R.row(7).cwiseAbs().maxCoeff(), 1e-6);
  const Eigen::MatrixXd H = dependent.transpose() * dependent;
  EXPECT_LT((a.R.transpose() * a.R - H).cwiseAbs().maxCoeff(), 1e-10 * H.cwiseAbs().maxCoeff());
  const Eigen::VectorXd g = dependent.transpose() * r;
  EXPECT_LT((a.R.transpose() * a.head - g).cwiseAbs().maxCoeff(), 1e-10 * g.cwiseAbs().maxCoeff());
  EXPECT_NEAR(a.head.squaredNorm() + a.rest * a.rest, r.squaredNorm(), 1e-12 * r.squaredNorm());
  // rest: r's distance to the columns' span (a rank-revealing least squares).
  const Eigen::VectorXd x = dependent.colPivHouseholderQr().solve(r);
  EXPECT_NEAR(a.rest, (r - dependent * x).norm(), 1e-10 * r.norm());

  const Eigen::VectorXd explained = A * Eigen::VectorXd::LinSpaced(n, -1.0, 1.0);
  const CompressedRows b = CompressRows(A, explained);
  EXPECT_FALSE(b.by_cholesky);
  EXPECT_LT(b.rest, 1e-12 * explained.norm());
  EXPECT_NEAR(b.head.norm(), explained.norm(), 1e-12 * explained.norm());
}

// What ParallelSegmentEvaluation relies on: a block prepared at a point (on
// any thread) and then evaluated there gives exactly what a block evaluated
// there from scratch gives, with or without Jacobians; preparing at one point
// and evaluating at another computes the other.
TEST(CompressedSegmentCost, APreparedBlockEqualsOneEvaluatedFromScratch) {
  const OneSegment one(8);
  const int P = one.free.size();
  auto block = [&] { return std::make_unique<CompressedSegmentCost>(one.Cost()); };
  Eigen::VectorXd s0 = InitialStateFromLog(one.log, one.first);
  Eigen::VectorXd s1 = InitialStateFromLog(one.log, one.last);
  s0[kW] += 0.05;
  Eigen::VectorXd theta = one.free.ScaledValues() * 1.05;
  const double* parameters[] = {s0.data(), theta.data(), s1.data()};
  const auto prepared = block();
  const auto fresh = block();
  // Jacobians: prepared on another thread, as the callback does.
  std::thread([&] { prepared->Prepare(parameters, true); }).join();
  const Block a = EvaluateBlock(*prepared, parameters, P);
  const Block b = EvaluateBlock(*fresh, parameters, P);
  EXPECT_TRUE((a.r.array() == b.r.array()).all());
  EXPECT_TRUE((a.J.array() == b.J.array()).all());
  // A trial point (no Jacobians), then a point it was not prepared at.
  const int m = prepared->num_residuals();
  Eigen::VectorXd r_prepared(m), r_fresh(m);
  theta[1] *= 1.02;
  std::thread([&] { prepared->Prepare(parameters, false); }).join();
  ASSERT_TRUE(prepared->Evaluate(parameters, r_prepared.data(), nullptr));
  ASSERT_TRUE(fresh->Evaluate(parameters, r_fresh.data(), nullptr));
  EXPECT_TRUE((r_prepared.array() == r_fresh.array()).all());
  EXPECT_GT((r_prepared - b.r).norm(), 0);  // a different point: different residuals
  theta[2] *= 1.02;
  ASSERT_TRUE(prepared->Evaluate(parameters, r_prepared.data(), nullptr));
  ASSERT_TRUE(fresh->Evaluate(parameters, r_fresh.data(), nullptr));
  EXPECT_TRUE((r_prepared.array() == r_fresh.array()).all());
}

}  // namespace
}  // namespace coaxid
