// The compressed segment block gives Ceres the full block's cost, gradient
// and normal equations (J^T J, J^T r); the output-error tests fit through it.
#include "ident/output_error/compressed_segment_cost.h"

#include <memory>
#include <thread>

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
